//! A finger profile: what a mission needs to read one finger, in one folder —
//! `recognition.ctm` and `width.ctm` (the models) and `card.toml` (the card: who, when, on
//! which plates, with how many slides, the optics, including the `[optics.fibre]` the mission
//! uses, and the figures). `crackbot run --finger PROFILE` reads it ([`FingerProfile::load`]);
//! the format is in `crates/mission/docs/finger-profile.md`.

use std::path::{Path, PathBuf};

use crackbot_recording::Experiment;
use crackbot_tactile::model::TactileModel;
use serde::{Deserialize, Serialize};

use super::error::{io, CommissionError};
use super::optics::FingerOptics;
use super::train::Evaluation;

/// The card's format version.
pub const CARD_VERSION: u32 = 1;

/// The profile's card.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FingerCard {
    /// The format's version ([`CARD_VERSION`]).
    pub version: u32,
    /// The finger's name.
    pub name: String,
    /// When it was commissioned (RFC 3339, UTC).
    pub date: String,
    /// The plates slid over.
    pub plates: Vec<String>,
    /// Repetitions of each plate.
    pub repetitions: u32,
    /// Slides per repetition.
    pub slides_per_repetition: u32,
    /// Slides recorded in all.
    pub slides: u64,
    /// Robot time: the approach and the slides, s.
    pub robot_time_s: [f64; 2],
    /// The optics.
    pub optics: FingerOptics,
    /// The models' figures.
    pub evaluation: Evaluation,
}

/// A profile read from its folder.
#[derive(Debug, Clone)]
pub struct FingerProfile {
    /// The folder.
    pub dir: PathBuf,
    /// The card.
    pub card: FingerCard,
    /// The recognition model's file.
    pub recognition_model: PathBuf,
    /// The width model's file.
    pub width_model: PathBuf,
}

impl FingerProfile {
    /// Reads and checks the profile in `dir`: the card, the fibre in range, both models
    /// loading as the experiments they are named for.
    pub fn load(dir: &Path) -> Result<FingerProfile, CommissionError> {
        let path = dir.join("card.toml");
        let text = std::fs::read_to_string(&path).map_err(io(&path))?;
        let bad = |message: String| CommissionError::BadFile {
            path: path.clone(),
            message,
        };
        let card: FingerCard = toml::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if card.version != CARD_VERSION {
            return Err(bad(format!(
                "card version {}, this build reads {CARD_VERSION}",
                card.version
            )));
        }
        card.optics
            .fibre
            .checked()
            .map_err(|e| bad(e.to_string()))?;
        let model = |name: &str, experiment: Experiment| -> Result<PathBuf, CommissionError> {
            let p = dir.join(name);
            let m = TactileModel::load(&p)?;
            if m.experiment() != experiment {
                return Err(CommissionError::BadFile {
                    path: p,
                    message: format!(
                        "a {} model, not {}",
                        m.experiment().name(),
                        experiment.name()
                    ),
                });
            }
            Ok(p)
        };
        Ok(FingerProfile {
            dir: dir.to_path_buf(),
            recognition_model: model("recognition.ctm", Experiment::Recognition)?,
            width_model: model("width.ctm", Experiment::Width)?,
            card,
        })
    }
}

/// Installs the profile into `dir` (created; a profile already there is replaced): the models
/// and the card, each written whole before the card that names them.
pub fn install(
    dir: &Path,
    card: &FingerCard,
    (recognition, width): (&TactileModel, &TactileModel),
) -> Result<(), CommissionError> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    recognition.save(&dir.join("recognition.ctm"))?;
    width.save(&dir.join("width.ctm"))?;
    let path = dir.join("card.toml");
    let text = toml::to_string_pretty(card).map_err(|e| CommissionError::BadFile {
        path: path.clone(),
        message: e.to_string(),
    })?;
    std::fs::write(&path, text).map_err(io(&path))
}
