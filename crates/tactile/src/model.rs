//! The deployed tactile model: what the robot loads to classify slides online
//! ([`crate::online`]), trained by `crackbot tactile train` on every recording it is given.
//!
//! One file per experiment (recognition, width) holds:
//!
//! * the **context forest** on the causal context features of each window ([`crate::context`],
//!   computed online by [`crate::stream::StreamingContext`]);
//! * the **window forest** on the paper's own window features (MAV of D1, D2, P), whose slide mean
//!   joins the slide verdict where the header's [`ModelHeader::slide_vote`] is
//!   [`SlideVote::Both`] (see [`crate::eval::test_classifier_with_slide_voters`]). The window
//!   features are absolute counts, so that forest also learns each plate's fibre offsets: the
//!   committed width model votes with the context forest alone (`models/tactile/MODEL_CARD.md`,
//!   "Who votes");
//! * for the width experiment, a **width regressor** (mm) on the context features;
//! * the **unknown-surface gate** ([`UnknownGate`]), fitted on the training windows;
//! * the pipeline (segmentation, windows, features, context) and what it was trained on.
//!
//! # File format (version 1)
//!
//! Little-endian: magic `b"CRKTACTL"` (8 bytes), format version `u32`, header length `u32`, the
//! header (UTF-8 JSON, [`ModelHeader`]), then each section the header lists, in order, each a
//! forest in the `CRKFORST` format of [`crackbot_forest::format`] (with its own CRC-32), then a
//! CRC-32 (ISO-HDLC) of every preceding byte. Loading checks magic, version, lengths, the
//! checksum, the header, every forest, and that the parts fit together (feature counts, classes,
//! pipeline); anything else is a [`TactileError::Model`] naming the file and what is wrong.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crackbot_forest::{
    Classifier, Dataset, ForestParams, RandomForest, RandomForestRegressor, RegressionDataset,
};
use crackbot_recording::Recording;
use serde::{Deserialize, Serialize};

use crate::context::ContextConfig;
use crate::dataset::{detect_experiment, Experiment, Pipeline, PipelineConfig, WindowSet};
pub use crate::vote::SlideVote;
use crate::TactileError;

/// Magic number at the start of every model file.
pub const MAGIC: [u8; 8] = *b"CRKTACTL";
/// Format version written by this build.
pub const FORMAT_VERSION: u32 = 1;
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
const CONTEXT_FOREST: &str = "context_forest";
const WINDOW_FOREST: &str = "window_forest";
const WIDTH_REGRESSOR: &str = "width_regressor";

/// The deployed pipeline: the paper's segmentation and windows, MAV of D1, D2, P, raw counts, and
/// the default context features.
pub fn deployed_pipeline() -> PipelineConfig {
    PipelineConfig {
        context: Some(ContextConfig::default()),
        ..PipelineConfig::default()
    }
}

/// How the deployed models are trained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    /// Trees of each forest (≥ 1).
    pub n_trees: usize,
    /// Depth limit of every tree (`None`: fully grown).
    pub max_depth: Option<usize>,
    /// Seed of the forests.
    pub seed: u64,
    /// Who decides a slide's verdict ([`ModelHeader::slide_vote`]). Files written before this
    /// setting existed read as [`SlideVote::Both`], the way they vote.
    #[serde(default)]
    pub slide_vote: SlideVote,
}

impl Default for TrainConfig {
    /// 100 trees, fully grown, seed 1, both forests voting.
    fn default() -> Self {
        TrainConfig {
            n_trees: 100,
            max_depth: None,
            seed: 1,
            slide_vote: SlideVote::Both,
        }
    }
}

/// What a model was trained on and how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingInfo {
    /// File names of the training recordings.
    pub recordings: Vec<String>,
    /// Training windows (context rows).
    pub windows: usize,
    /// Training slides with windows.
    pub slides: usize,
    /// Forest settings.
    pub config: TrainConfig,
    /// Wall-clock training time of every forest, seconds.
    pub seconds: f64,
    /// crackbot version that trained it.
    pub crackbot_version: String,
}

/// When a slide is "unknown": a surface or a signal unlike anything in training.
///
/// Fitted on the training windows ([`UnknownGate::fit`]): per context feature, the 0.1 % and
/// 99.9 % quantiles of the training rows widened by a quarter of their distance (a window is
/// *novel* when any feature falls outside); per channel, the range of the raw training samples
/// widened by a quarter of it. At the end of a slide ([`UnknownGate::judge`]): a channel of the
/// model that stays within `dead_range` counts over the whole slide is dead; samples outside the
/// raw range are saturated or mis-mounted; more than `max_novel_fraction` novel windows is a
/// surface unlike training; a slide vote below `min_confidence` is low confidence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnknownGate {
    /// Lower limit of each context feature.
    pub feature_low: Vec<f32>,
    /// Upper limit of each context feature.
    pub feature_high: Vec<f32>,
    /// Largest fraction of novel windows of a known slide.
    pub max_novel_fraction: f64,
    /// Lower limit of each raw channel `[D1, D2, D3, P]`, counts.
    pub sample_low: [f64; 4],
    /// Upper limit of each raw channel, counts.
    pub sample_high: [f64; 4],
    /// Largest fraction of a slide's samples outside the raw limits.
    pub max_outside_fraction: f64,
    /// A channel whose slide range (max − min) is at most this is dead, counts.
    pub dead_range: f64,
    /// Slide verdicts whose vote is below this are low confidence.
    pub min_confidence: f64,
}

/// Why a slide's verdict is not to be trusted.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Doubt {
    /// A channel the model uses did not move over the slide.
    DeadChannel {
        /// `D1`, `D2`, `D3` or `P`.
        channel: &'static str,
    },
    /// Too many samples outside the training range (saturation, another mounting).
    OutOfRange {
        /// The channel with most samples out.
        channel: &'static str,
        /// Fraction of the slide's samples out of range.
        fraction: f64,
    },
    /// Too many windows unlike any training window.
    Novel {
        /// Fraction of novel windows.
        fraction: f64,
    },
    /// The vote is too weak.
    LowConfidence {
        /// The winning class's vote.
        confidence: f64,
    },
}

impl Doubt {
    /// Whether the surface is unknown (not merely a weak vote).
    pub fn is_unknown(&self) -> bool {
        !matches!(self, Doubt::LowConfidence { .. })
    }
}

const CHANNEL_NAMES: [&str; 4] = ["D1", "D2", "D3", "P"];

impl UnknownGate {
    /// Fits the limits on the training context rows and raw samples.
    pub fn fit(set: &WindowSet, recordings: &[(PathBuf, Recording)], channels: &[usize]) -> Self {
        let nf = set.n_features;
        let n = set.n_rows();
        let mut feature_low = vec![0f32; nf];
        let mut feature_high = vec![0f32; nf];
        let mut column = Vec::with_capacity(n);
        for f in 0..nf {
            column.clear();
            column.extend((0..n).map(|i| set.x[i * nf + f]));
            column.sort_by(f32::total_cmp);
            let q = |p: f64| column[((p * (n.max(1) - 1) as f64).round() as usize).min(n - 1)];
            let (lo, hi) = if n == 0 {
                (0.0, 0.0)
            } else {
                (q(0.001), q(0.999))
            };
            let margin = 0.25 * (hi - lo);
            feature_low[f] = lo - margin;
            feature_high[f] = hi + margin;
        }
        let mut sample_low = [f64::INFINITY; 4];
        let mut sample_high = [f64::NEG_INFINITY; 4];
        for (_, rec) in recordings {
            for r in &rec.rows {
                for (c, v) in r.channels().into_iter().enumerate() {
                    sample_low[c] = sample_low[c].min(v);
                    sample_high[c] = sample_high[c].max(v);
                }
            }
        }
        for c in 0..4 {
            if !channels.contains(&c) || !sample_low[c].is_finite() {
                // Channels the model does not use are not judged.
                sample_low[c] = -f64::MAX;
                sample_high[c] = f64::MAX;
                continue;
            }
            let margin = 0.25 * (sample_high[c] - sample_low[c]);
            sample_low[c] -= margin;
            sample_high[c] += margin;
        }
        UnknownGate {
            feature_low,
            feature_high,
            max_novel_fraction: 0.2,
            sample_low,
            sample_high,
            max_outside_fraction: 0.05,
            dead_range: 1.0,
            min_confidence: 0.5,
        }
    }

    /// Whether a context row has a feature outside its limits.
    #[inline]
    pub fn is_novel(&self, row: &[f32]) -> bool {
        row.iter()
            .zip(self.feature_low.iter().zip(&self.feature_high))
            .any(|(v, (lo, hi))| !(v >= lo && v <= hi))
    }

    /// The doubt about a slide, if any: `samples` the slide's raw samples, `channels` the model's,
    /// `novel` the fraction of its windows that are novel, `confidence` its vote.
    pub fn judge(
        &self,
        samples: &[[f64; 4]],
        channels: &[usize],
        novel: f64,
        confidence: f64,
    ) -> Option<Doubt> {
        let n = samples.len().max(1) as f64;
        for &c in channels {
            let (lo, hi) = samples
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| {
                    (l.min(s[c]), h.max(s[c]))
                });
            if !samples.is_empty() && hi - lo <= self.dead_range {
                return Some(Doubt::DeadChannel {
                    channel: CHANNEL_NAMES[c],
                });
            }
        }
        let worst = channels
            .iter()
            .map(|&c| {
                let out = samples
                    .iter()
                    .filter(|s| !(s[c] >= self.sample_low[c] && s[c] <= self.sample_high[c]))
                    .count();
                (c, out as f64 / n)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((c, fraction)) = worst {
            if fraction > self.max_outside_fraction {
                return Some(Doubt::OutOfRange {
                    channel: CHANNEL_NAMES[c],
                    fraction,
                });
            }
        }
        if novel > self.max_novel_fraction {
            return Some(Doubt::Novel { fraction: novel });
        }
        if confidence < self.min_confidence {
            return Some(Doubt::LowConfidence { confidence });
        }
        None
    }
}

/// One section of a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Section {
    /// `context_forest`, `window_forest` or `width_regressor`.
    pub name: String,
    /// Its length in bytes.
    pub bytes: usize,
}

/// The JSON header of a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelHeader {
    /// The file format version (again, for readers of the JSON alone).
    pub format_version: u32,
    /// The experiment the model classifies.
    pub experiment: Experiment,
    /// Class names, in class order.
    pub classes: Vec<String>,
    /// Label of each class (class id, or crack width in mm).
    pub labels: Vec<f64>,
    /// Segmentation, windows, features, context.
    pub pipeline: PipelineConfig,
    /// Values per context row.
    pub n_context_features: usize,
    /// Values per window row (the paper's features).
    pub n_window_features: usize,
    /// The unknown-surface gate.
    pub gate: UnknownGate,
    /// Who decides a slide's verdict: the context forest alone ([`SlideVote::Context`]), or the
    /// context forest and the window forest, their slide means summed ([`SlideVote::Both`]; what
    /// files written before this field do, hence the default).
    #[serde(default)]
    pub slide_vote: SlideVote,
    /// What it was trained on.
    pub training: TrainingInfo,
    /// The forests that follow the header, in order.
    pub sections: Vec<Section>,
}

/// A deployed tactile model (see the [module docs](self)).
#[derive(Debug, Clone)]
pub struct TactileModel {
    /// Everything but the forests.
    pub header: ModelHeader,
    /// Classifier on the context rows.
    pub context_forest: RandomForest,
    /// Classifier on the paper's window rows.
    pub window_forest: RandomForest,
    /// Width regressor on the context rows (width experiment).
    pub width: Option<RandomForestRegressor>,
}

/// Reports progress of training: `(forest name, trees done, trees in all)`.
pub type ModelProgress<'a> = &'a mut (dyn FnMut(&'static str, usize, usize) + Send);

/// What a model records of its training: the recordings' names, the windows and slides of the
/// context `set`, the `config`, and the seconds since `started`.
fn training_info(
    recordings: &[(PathBuf, Recording)],
    set: &WindowSet,
    config: &TrainConfig,
    started: Instant,
) -> TrainingInfo {
    TrainingInfo {
        recordings: recordings
            .iter()
            .map(|(p, _)| {
                p.file_name()
                    .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into())
            })
            .collect(),
        windows: set.n_rows(),
        slides: set.slides.iter().filter(|s| !s.windows.is_empty()).count(),
        config: config.clone(),
        // To the millisecond: a number of few digits reads back from the JSON header exactly
        // (serde_json's default parser can miss a 17-digit one by an ulp).
        seconds: (started.elapsed().as_secs_f64() * 1e3).round() / 1e3,
        crackbot_version: env!("CARGO_PKG_VERSION").to_string(),
    }
}

impl TactileModel {
    /// Trains the deployed models on every slide of `recordings` (the experiment detected from
    /// their labels unless given).
    pub fn train(
        recordings: &[(PathBuf, Recording)],
        experiment: Option<Experiment>,
        config: &TrainConfig,
        progress: ModelProgress<'_>,
    ) -> Result<Self, TactileError> {
        Self::train_with_pipeline(
            recordings,
            experiment,
            config,
            deployed_pipeline(),
            progress,
        )
    }

    /// [`Self::train`] with another pipeline than [`deployed_pipeline`] (it must have context
    /// features).
    pub fn train_with_pipeline(
        recordings: &[(PathBuf, Recording)],
        experiment: Option<Experiment>,
        config: &TrainConfig,
        pipeline_config: PipelineConfig,
        progress: ModelProgress<'_>,
    ) -> Result<Self, TactileError> {
        crate::error::check_n_trees(config.n_trees)?;
        let experiment = match experiment {
            Some(e) => e,
            None => detect_experiment(recordings)?,
        };
        let pipeline = pipeline_config.check()?;
        let started = Instant::now();
        let context_set = pipeline.build_windows(recordings, experiment)?;
        let window_set = pipeline
            .without_context()
            .build_windows(recordings, experiment)?;
        let k = experiment.n_classes();
        let params = |p: ForestParams| {
            p.n_trees(config.n_trees)
                .seed(config.seed)
                .max_depth(config.max_depth)
        };
        let data = Dataset::with_classes(
            context_set.x.clone(),
            context_set.n_features,
            context_set.y.clone(),
            k,
        )?;
        let context_forest = RandomForest::fit_with_progress(
            &data,
            &params(ForestParams::classifier()),
            &mut |d, t| progress(CONTEXT_FOREST, d, t),
        )?
        .with_class_labels(experiment.labels().to_vec())?;
        let data = Dataset::with_classes(
            window_set.x.clone(),
            window_set.n_features,
            window_set.y.clone(),
            k,
        )?;
        let window_forest = RandomForest::fit_with_progress(
            &data,
            &params(ForestParams::classifier()),
            &mut |d, t| progress(WINDOW_FOREST, d, t),
        )?
        .with_class_labels(experiment.labels().to_vec())?;
        let width = match experiment {
            Experiment::Recognition => None,
            Experiment::Width => {
                let y: Vec<f32> = context_set.label.iter().map(|&l| l as f32).collect();
                let data =
                    RegressionDataset::new(context_set.x.clone(), context_set.n_features, y)?;
                Some(RandomForestRegressor::fit_with_progress(
                    &data,
                    &params(ForestParams::regressor()),
                    &mut |d, t| progress(WIDTH_REGRESSOR, d, t),
                )?)
            }
        };
        let channels = pipeline_config.spec.set.channels().to_vec();
        let gate = UnknownGate::fit(&context_set, recordings, &channels);
        let training = training_info(recordings, &context_set, config, started);
        let header = ModelHeader {
            format_version: FORMAT_VERSION,
            experiment,
            classes: experiment
                .class_names()
                .iter()
                .map(std::string::ToString::to_string)
                .collect(),
            labels: experiment.labels().to_vec(),
            n_context_features: context_set.n_features,
            n_window_features: window_set.n_features,
            pipeline: pipeline_config,
            gate,
            slide_vote: config.slide_vote,
            training,
            sections: Vec::new(),
        };
        let model = TactileModel {
            header,
            context_forest,
            window_forest,
            width,
        };
        model.check(Path::new("<memory>"))?;
        Ok(model)
    }

    /// The experiment.
    pub fn experiment(&self) -> Experiment {
        self.header.experiment
    }

    /// The checked pipeline of the model.
    pub fn pipeline(&self) -> Result<Pipeline, TactileError> {
        self.header.pipeline.check()
    }

    /// The context configuration (always present in a deployed model).
    pub fn context(&self) -> &ContextConfig {
        // `check` refuses a header without context; this default is never used.
        static DEFAULT: std::sync::OnceLock<ContextConfig> = std::sync::OnceLock::new();
        self.header
            .pipeline
            .context
            .as_ref()
            .unwrap_or_else(|| DEFAULT.get_or_init(ContextConfig::default))
    }

    /// Checks that the parts fit together.
    fn check(&self, path: &Path) -> Result<(), TactileError> {
        let bad = |reason: String| TactileError::Model {
            path: path.to_path_buf(),
            reason,
        };
        let h = &self.header;
        if h.format_version != FORMAT_VERSION {
            return Err(bad(format!(
                "header says format version {}, this build reads {FORMAT_VERSION}",
                h.format_version
            )));
        }
        let Some(context) = &h.pipeline.context else {
            return Err(bad("the pipeline has no context features".into()));
        };
        h.pipeline
            .check()
            .map_err(|e| bad(format!("the pipeline is invalid: {e}")))?;
        if h.pipeline.normalisation != crate::dataset::Normalisation::None {
            return Err(bad(
                "a recording-wide normalisation cannot be computed online".into(),
            ));
        }
        if context.keep_window || context.shape {
            return Err(bad(
                "context features with keep_window or shape have no streaming form".into(),
            ));
        }
        let channels = h.pipeline.spec.set.channels().len();
        let k = h.experiment.n_classes();
        let expect_ctx = context.n_context(channels);
        let expect_win = h.pipeline.spec.n_features();
        let mut problems = Vec::new();
        if h.n_context_features != expect_ctx {
            problems.push(format!(
                "the header says {} context features, its pipeline makes {expect_ctx}",
                h.n_context_features
            ));
        }
        if self.context_forest.n_features() != expect_ctx || self.context_forest.n_classes() != k {
            problems.push(format!(
                "the context forest takes {} features and {} classes, the pipeline makes {expect_ctx} features and the {} experiment has {k} classes",
                self.context_forest.n_features(),
                self.context_forest.n_classes(),
                h.experiment.name()
            ));
        }
        if self.window_forest.n_features() != expect_win || self.window_forest.n_classes() != k {
            problems.push(format!(
                "the window forest takes {} features and {} classes, expected {expect_win} and {k}",
                self.window_forest.n_features(),
                self.window_forest.n_classes()
            ));
        }
        match (&self.width, h.experiment) {
            (Some(w), Experiment::Width) if w.n_features() != expect_ctx => problems.push(format!(
                "the width regressor takes {} features, expected {expect_ctx}",
                w.n_features()
            )),
            (None, Experiment::Width) => {
                problems.push("a width model without its regressor".into());
            }
            (Some(_), Experiment::Recognition) => {
                problems.push("a recognition model with a width regressor".into());
            }
            _ => {}
        }
        if h.classes.len() != k || h.labels.as_slice() != h.experiment.labels() {
            problems.push(format!(
                "classes {:?} / labels {:?} are not those of the {} experiment",
                h.classes,
                h.labels,
                h.experiment.name()
            ));
        }
        let g = &h.gate;
        if g.feature_low.len() != expect_ctx || g.feature_high.len() != expect_ctx {
            problems.push(format!(
                "the unknown-surface gate has {} limits, expected {expect_ctx}",
                g.feature_low.len()
            ));
        }
        match problems.is_empty() {
            true => Ok(()),
            false => Err(bad(problems.join("; "))),
        }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>, TactileError> {
        let mut sections: Vec<(&str, Vec<u8>)> = vec![
            (CONTEXT_FOREST, self.context_forest.to_bytes()),
            (WINDOW_FOREST, self.window_forest.to_bytes()),
        ];
        if let Some(w) = &self.width {
            sections.push((WIDTH_REGRESSOR, w.to_bytes()));
        }
        let mut header = self.header.clone();
        header.sections = sections
            .iter()
            .map(|(n, b)| Section {
                name: n.to_string(),
                bytes: b.len(),
            })
            .collect();
        let json = serde_json::to_vec(&header)?;
        let mut out = Vec::with_capacity(
            16 + json.len() + sections.iter().map(|s| s.1.len()).sum::<usize>() + 4,
        );
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        for (_, b) in &sections {
            out.extend_from_slice(b);
        }
        let crc = CRC.checksum(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        Ok(out)
    }

    /// Reads a model from `bytes`; `path` names it in errors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, TactileError> {
        let bad = |reason: String| TactileError::Model {
            path: path.to_path_buf(),
            reason,
        };
        if bytes.len() < 8 || bytes[..8] != MAGIC {
            return Err(bad(
                "not a crackbot tactile model (no CRKTACTL magic at the start)".into(),
            ));
        }
        let u32_at = |at: usize| -> Option<u32> {
            bytes
                .get(at..at + 4)
                .and_then(|b| b.try_into().ok())
                .map(u32::from_le_bytes)
        };
        let version = u32_at(8).ok_or_else(|| bad("truncated in the header".into()))?;
        if version != FORMAT_VERSION {
            return Err(bad(format!(
                "format version {version}; this build reads version {FORMAT_VERSION} (retrain with `crackbot tactile train`)"
            )));
        }
        let header_len = u32_at(12).ok_or_else(|| bad("truncated in the header".into()))? as usize;
        if bytes.len() < 16 + 4 {
            return Err(bad("truncated in the header".into()));
        }
        let body = &bytes[..bytes.len() - 4];
        let stored = u32_at(bytes.len() - 4).unwrap_or(0);
        let header_bytes = body.get(16..16 + header_len).ok_or_else(|| {
            bad(format!(
                "truncated: the header says {header_len} bytes of JSON, the file has {} in all",
                bytes.len()
            ))
        })?;
        let header: ModelHeader = serde_json::from_slice(header_bytes).map_err(|e| {
            if CRC.checksum(body) != stored {
                bad("corrupt: the header is not valid JSON and the checksum does not match".into())
            } else {
                bad(format!(
                    "the header is not a model header of this version: {e}"
                ))
            }
        })?;
        let expected: usize =
            16 + header_len + header.sections.iter().map(|s| s.bytes).sum::<usize>() + 4;
        if bytes.len() != expected {
            return Err(bad(format!(
                "{} bytes, but its header announces {expected}: truncated or trailing data",
                bytes.len()
            )));
        }
        let computed = CRC.checksum(body);
        if computed != stored {
            return Err(bad(format!(
                "corrupt: checksum {computed:08x} of the content, {stored:08x} stored"
            )));
        }
        let mut at = 16 + header_len;
        let mut context_forest = None;
        let mut window_forest = None;
        let mut width = None;
        for s in &header.sections {
            let part = &body[at..at + s.bytes];
            at += s.bytes;
            let forest_err =
                |e: crackbot_forest::ForestError| bad(format!("section {}: {e}", s.name));
            match s.name.as_str() {
                CONTEXT_FOREST => {
                    context_forest = Some(RandomForest::from_bytes(part).map_err(forest_err)?);
                }
                WINDOW_FOREST => {
                    window_forest = Some(RandomForest::from_bytes(part).map_err(forest_err)?);
                }
                WIDTH_REGRESSOR => {
                    width = Some(RandomForestRegressor::from_bytes(part).map_err(forest_err)?);
                }
                other => return Err(bad(format!("unknown section {other:?}"))),
            }
        }
        let (Some(context_forest), Some(window_forest)) = (context_forest, window_forest) else {
            return Err(bad(
                "a context forest and a window forest are both needed".into()
            ));
        };
        let model = TactileModel {
            header,
            context_forest,
            window_forest,
            width,
        };
        model.check(path)?;
        Ok(model)
    }

    /// Writes the model to `path`.
    pub fn save(&self, path: &Path) -> Result<(), TactileError> {
        let bytes = self.to_bytes()?;
        std::fs::write(path, bytes).map_err(|source| TactileError::Io {
            action: "writing",
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads the model at `path`.
    pub fn load(path: &Path) -> Result<Self, TactileError> {
        let bytes = std::fs::read(path).map_err(|source| TactileError::Io {
            action: "reading",
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, path)
    }
}
