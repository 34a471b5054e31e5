//! Commissioning a new finger: its optics read, the papers' reference plates slid over, its own
//! models trained and evaluated, and a finger profile installed that missions use
//! (`crackbot commission`, `crackbot run --finger PROFILE`).
//!
//! The steps, one file each, in the order [`commission`] runs them:
//! * `settings.rs`: which plates, repetitions, slides; checked once;
//! * `session.rs`: the session's folder, from which an interrupted run resumes;
//! * `on_rig.rs`: one session of the rig per mounted plate (hardware, or the simulated rig);
//! * `approach.rs` then `optics.rs`: the optics over bare plate, fitted;
//! * `record.rs`: the papers' protocol on each plate;
//! * `train.rs`: the models, leave-one-repetition-out figures, the shipped models beside them;
//! * `profile.rs`: the profile installed, and read back by missions.

mod approach;
mod error;
mod on_rig;
mod optics;
mod profile;
mod record;
mod session;
mod settings;
mod train;

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crackbot_plates::ReferencePlate;
use crackbot_recording::Experiment;
use crackbot_tactile::model::TactileModel;

pub use approach::{ApproachReadings, DARK_HOVER_MM, HOVERS_MM};
pub use error::CommissionError;
pub use optics::{check_saturation, fit_optics, FingerOptics};
pub use profile::{install, FingerCard, FingerProfile, CARD_VERSION};
pub use record::{slide_lines, SlideLine, START_BEFORE_EDGE_MM};
pub use session::{OpticsFile, Session};
pub use settings::{CommissionSettings, REPETITIONS, SLIDES, SPEED_MM_S, STROKE_MM};
pub use train::{Evaluation, Figures};

use crate::inspect::rig::feel::Feel;
use crate::inspect::RigConfig;
use session::OpticsFile as Optics;
use train::SessionRecording;

/// What a commissioning is given.
#[derive(Debug, Clone)]
pub struct CommissionConfig {
    /// What it does.
    pub settings: CommissionSettings,
    /// Its folder (resumed when it holds a session with the same settings).
    pub session: PathBuf,
    /// Where the profile is installed.
    pub profile: PathBuf,
    /// The finger's name, for its card.
    pub name: String,
    /// The date, for its card (RFC 3339).
    pub date: String,
    /// The shipped models, measured beside the new ones.
    pub shipped: (PathBuf, PathBuf),
}

/// What a commissioning reports as it goes.
#[derive(Debug, Clone, PartialEq)]
pub enum CommissionProgress {
    /// Reading the optics over bare plate.
    Approach,
    /// The optics, read (or resumed).
    Optics(FingerOptics),
    /// Sliding over a plate: its name, and the slides done of all (the session's).
    Slides {
        /// The plate mounted.
        plate: String,
        /// Slides done, the session's.
        done: u64,
        /// Slides in all.
        total: u64,
    },
    /// A model being trained or evaluated: what.
    Training(String),
    /// The figures.
    Evaluated(Evaluation),
}

/// Where each plate is: the rig to use with it mounted. On hardware the operator mounts it
/// (the front end asks, then returns its rig); on the simulator the scene becomes the plate.
pub trait Mounts {
    /// The rig with `plate` mounted.
    fn mount(&mut self, plate: &ReferencePlate) -> Result<RigConfig, CommissionError>;
}

/// What a commissioning did.
#[derive(Debug, Clone, PartialEq)]
pub struct CommissionReport {
    /// The installed profile's card.
    pub card: FingerCard,
    /// The profile's folder.
    pub profile: PathBuf,
}

/// Runs a commissioning (see the [module docs](self)).
pub fn commission(
    config: &CommissionConfig,
    mounts: &mut dyn Mounts,
    stop: &AtomicBool,
    progress: &mut dyn FnMut(&CommissionProgress),
) -> Result<CommissionReport, CommissionError> {
    let plates = config.settings.check()?;
    let session = Session::open(&config.session, &config.settings)?;
    let shipped = (
        TactileModel::load(&config.shipped.0)?,
        TactileModel::load(&config.shipped.1)?,
    );
    let mut feel = Feel::new(&shipped.0, &shipped.1)?;
    let (optics, approach_s) = optics_step(&session, mounts, stop, &mut feel, progress)?;
    let (recordings, slides_s) = record_step(
        &session,
        &plates,
        (mounts, stop),
        &config.settings,
        &mut feel,
        progress,
    )?;
    let (recognition, width, evaluation) =
        train_step(&session, &recordings, &config.settings, &shipped, progress)?;
    train::judge(&evaluation, &config.settings, session.dir())?;
    let s = &config.settings;
    let card = FingerCard {
        version: CARD_VERSION,
        name: config.name.clone(),
        date: config.date.clone(),
        plates: plates.iter().map(|p| p.name.clone()).collect(),
        repetitions: s.repetitions,
        slides_per_repetition: s.slides,
        slides: recordings.len() as u64 * u64::from(s.slides),
        robot_time_s: [approach_s, slides_s],
        optics: optics.optics,
        evaluation,
    };
    install(&config.profile, &card, (&recognition, &width))?;
    Ok(CommissionReport {
        card,
        profile: config.profile.clone(),
    })
}

/// Robot time of a rig session that took `wall` at `speedup`, s.
fn robot_s(started: Instant, speedup: f64) -> f64 {
    started.elapsed().as_secs_f64() * speedup
}

/// The optics over the flat plate, or the session's; and the robot time it took.
fn optics_step(
    session: &Session,
    mounts: &mut dyn Mounts,
    stop: &AtomicBool,
    feel: &mut Feel<'_>,
    progress: &mut dyn FnMut(&CommissionProgress),
) -> Result<(Optics, f64), CommissionError> {
    if let Some(o) = session.optics()? {
        progress(&CommissionProgress::Optics(o.optics.clone()));
        return Ok((o, 0.0));
    }
    progress(&CommissionProgress::Approach);
    let flat = crackbot_plates::by_name("flat").expect("the set has a flat plate");
    let rig = mounts.mount(&flat)?;
    let started = Instant::now();
    let at = [30.0, flat.surface.size_mm[1] / 2.0];
    let (readings, samples) = on_rig::on_rig(&rig, &session.rig_dir("approach"), stop, |r| {
        approach::approach(r, at, SPEED_MM_S, feel)
    })?;
    let took = robot_s(started, rig.speedup);
    check_saturation("the flat plate (the approach)", &samples)?;
    let optics = fit_optics(&readings, rig.site.fibre)?;
    let file = Optics { readings, optics };
    session.save_optics(&file)?;
    progress(&CommissionProgress::Optics(file.optics.clone()));
    Ok((file, took))
}

/// Every plate's repetitions, slid where the session lacks them; all of them, and the robot
/// time the slides took.
fn record_step(
    session: &Session,
    plates: &[ReferencePlate],
    (mounts, stop): (&mut dyn Mounts, &AtomicBool),
    s: &CommissionSettings,
    feel: &mut Feel<'_>,
    progress: &mut dyn FnMut(&CommissionProgress),
) -> Result<(Vec<SessionRecording>, f64), CommissionError> {
    let total = plates.len() as u64 * u64::from(s.repetitions * s.slides);
    let (mut out, mut robot) = (Vec::new(), 0.0);
    for plate in plates {
        let missing = resumed(session, plate, s.repetitions, &mut out)?;
        let mut done = out.len() as u64 * u64::from(s.slides);
        let mut tell = |done: u64| {
            progress(&CommissionProgress::Slides {
                plate: plate.name.clone(),
                done,
                total,
            });
        };
        tell(done);
        if missing.is_empty() {
            continue;
        }
        let rig = mounts.mount(plate)?;
        let started = Instant::now();
        let label = f64::from(plate.recognition_label);
        let recorded = on_rig::on_rig(&rig, &session.rig_dir(&plate.name), stop, |r| {
            let mut got = Vec::new();
            for &rep in &missing {
                let mut slid = || {
                    done += 1;
                    tell(done);
                };
                let rec = record::record_repetition(r, (plate, rep, label), s, feel, &mut slid)?;
                // Checked, then kept, as each repetition ends: an interruption loses at most
                // one, and a saturated one is never kept.
                check_recording(plate, &rec)?;
                session.save_recording(plate, rep, &rec)?;
                got.push((plate.clone(), rep, rec));
            }
            Ok::<_, CommissionError>(got)
        })?;
        robot += robot_s(started, rig.speedup);
        out.extend(recorded);
    }
    out.sort_by(|a, b| (a.0.name.as_str(), a.1).cmp(&(b.0.name.as_str(), b.1)));
    Ok((out, robot))
}

/// The repetitions of `plate` the session holds, checked as fresh ones are and added to
/// `out`; those it lacks.
fn resumed(
    session: &Session,
    plate: &ReferencePlate,
    repetitions: u32,
    out: &mut Vec<SessionRecording>,
) -> Result<Vec<u32>, CommissionError> {
    let mut missing = Vec::new();
    for rep in 1..=repetitions {
        match session.recording(plate, rep)? {
            Some(r) => {
                check_recording(plate, &r)?;
                out.push((plate.clone(), rep, r));
            }
            None => missing.push(rep),
        }
    }
    Ok(missing)
}

/// Refuses a recording of `plate` in which a channel saturates.
fn check_recording(
    plate: &ReferencePlate,
    rec: &crackbot_recording::Recording,
) -> Result<(), CommissionError> {
    let samples: Vec<[f64; 4]> = rec
        .rows
        .iter()
        .map(crackbot_recording::Row::channels)
        .collect();
    check_saturation(&plate.name, &samples)
}

/// Both models trained on everything, their held-out figures and the shipped models' beside
/// them (kept as `evaluation.json`).
fn train_step(
    session: &Session,
    recordings: &[SessionRecording],
    s: &CommissionSettings,
    shipped: &(TactileModel, TactileModel),
    progress: &mut dyn FnMut(&CommissionProgress),
) -> Result<(TactileModel, TactileModel, Evaluation), CommissionError> {
    let (rec_set, width_set) = train::labelled(recordings);
    let mut fold = |what: &str, rep: u32| {
        progress(&CommissionProgress::Training(format!(
            "{what}: repetition {rep} held out"
        )));
    };
    let recognition_figures =
        train::leave_one_repetition_out(&rec_set, Experiment::Recognition, s, &mut |r| {
            fold("recognition", r);
        })?;
    let width_figures =
        train::leave_one_repetition_out(&width_set, Experiment::Width, s, &mut |r| {
            fold("width", r);
        })?;
    progress(&CommissionProgress::Training(
        "both models on every repetition".into(),
    ));
    let recognition = train::train(&rec_set, Experiment::Recognition, s)?;
    let width = train::train(&width_set, Experiment::Width, s)?;
    let evaluation = Evaluation {
        recognition: recognition_figures,
        width: width_figures,
        shipped_recognition: train::figures(&shipped.0, &rec_set)?,
        shipped_width: train::figures(&shipped.1, &width_set)?,
    };
    session.save_json("evaluation.json", &evaluation)?;
    progress(&CommissionProgress::Evaluated(evaluation.clone()));
    Ok((recognition, width, evaluation))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_recording::{Recording, Row};

    fn recording(p: f64) -> Recording {
        let row = |i: u32| Row {
            x_mm: f64::from(i) * 0.01,
            d1: 650.0,
            d2: 430.0,
            d3: 700.0,
            p,
            direction: 1,
            slide: 1,
            label: 0.0,
            repetition: 1,
        };
        Recording {
            rows: (0..200).map(row).collect(),
            extra: None,
        }
    }

    #[test]
    fn a_resumed_repetition_that_saturates_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let settings = CommissionSettings::default();
        let session = Session::open(dir.path(), &settings).unwrap();
        let flat = crackbot_plates::by_name("flat").unwrap();
        session.save_recording(&flat, 1, &recording(500.0)).unwrap();
        let mut out = Vec::new();
        let missing = resumed(&session, &flat, 3, &mut out).unwrap();
        assert_eq!((out.len(), missing), (1, vec![2, 3]));
        session
            .save_recording(&flat, 2, &recording(1023.0))
            .unwrap();
        let e = resumed(&session, &flat, 3, &mut Vec::new()).unwrap_err();
        assert!(
            matches!(&e, CommissionError::Saturated { plate, channel: "P", .. } if plate == "flat"),
            "{e}"
        );
    }
}
