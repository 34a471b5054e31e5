//! The crate's error type.

use std::path::PathBuf;

use crackbot_dsp::DspError;
use crackbot_forest::ForestError;
use crackbot_recording::{Experiment, ExperimentError, RecordingError};

/// Everything that can go wrong in the tactile pipeline. Errors of the crates below keep their type
/// (as the source, or passed through unchanged); every variant about a file or a slide names it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TactileError {
    /// A classifier or regressor could not be trained or applied.
    #[error(transparent)]
    Forest(#[from] ForestError),
    /// A recording could not be read or written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The labels do not tell which experiment the recordings belong to.
    #[error(transparent)]
    Experiment(#[from] ExperimentError),
    /// The pipeline's segmentation or window parameters are invalid (checked once, before any slide).
    #[error(transparent)]
    Pipeline(DspError),
    /// The segmentation of one slide failed.
    #[error("{}: slide {slide}: segmentation failed: {source}", path.display())]
    Segmentation {
        /// The recording.
        path: PathBuf,
        /// The slide number (column 7).
        slide: u32,
        /// Why.
        #[source]
        source: DspError,
    },
    /// The feature windows of one slide could not be computed (e.g. a non-finite sample).
    #[error("{}: slide {slide}: {source}", path.display())]
    Features {
        /// The recording.
        path: PathBuf,
        /// The slide number (column 7).
        slide: u32,
        /// Why.
        #[source]
        source: DspError,
    },
    /// The context-feature configuration is invalid ([`crate::context::ContextConfig::validate`]).
    #[error("{reason}")]
    Context {
        /// What is wrong.
        reason: &'static str,
    },
    /// A recording's label is not the same on every row.
    #[error("{}: the label (column 8) is not constant over the recording", path.display())]
    MixedLabels {
        /// The recording.
        path: PathBuf,
    },
    /// A recording's repetition number is not the same on every row.
    #[error("{}: the repetition (column 9) is not constant", path.display())]
    MixedRepetitions {
        /// The recording.
        path: PathBuf,
    },
    /// A recording's label is not a class of the experiment.
    #[error("{}: label {label} is not a class of the {} experiment", path.display(), experiment.name())]
    UnknownLabel {
        /// The recording.
        path: PathBuf,
        /// Its label.
        label: f64,
        /// The experiment.
        experiment: Experiment,
    },
    /// Segmentation and the minimum slide length left no window at all.
    #[error("no feature window: every slide was too short or segmented away")]
    NoWindows,
    /// The intersession protocol found fewer than two repetitions.
    #[error(
        "the intersession protocol needs recordings of at least two repetitions, found {found:?}"
    )]
    TooFewRepetitions {
        /// The repetitions found.
        found: Vec<u32>,
    },
    /// A model does not fit the windows it is applied to.
    #[error(
        "the model has {model_classes} classes and {model_features} features, the test set {set_classes} and {set_features}"
    )]
    ModelMismatch {
        /// Classes of the model.
        model_classes: usize,
        /// Features of the model.
        model_features: usize,
        /// Classes of the window set's experiment.
        set_classes: usize,
        /// Features of the window set.
        set_features: usize,
    },
    /// A deployed tactile model file that cannot be used: not one, truncated, corrupt, another
    /// format version, or parts that do not fit together.
    #[error("{}: {reason}", path.display())]
    Model {
        /// The model file (or `<memory>`).
        path: PathBuf,
        /// What is wrong, in words.
        reason: String,
    },
    /// Recordings of one experiment given to a model of the other.
    #[error(
        "the model classifies the {model} experiment, the recordings are of the {data} experiment"
    )]
    ExperimentMismatch {
        /// The model's experiment.
        model: &'static str,
        /// The recordings' experiment.
        data: &'static str,
    },
    /// A slide voter's windows do not cut the test recordings as the test set does.
    #[error("slide voter {voter}: {detail}")]
    SlideVoter {
        /// Index of the voter.
        voter: usize,
        /// What differs, naming the first slide that does.
        detail: String,
    },
    /// Two window sets that must match (training and test of one grid) do not.
    #[error(
        "training windows ({} experiment, {train_features} features) and test windows ({} experiment, {test_features} features) differ",
        train_experiment.name(),
        test_experiment.name()
    )]
    WindowSetMismatch {
        /// Experiment of the training windows.
        train_experiment: Experiment,
        /// Features of the training windows.
        train_features: usize,
        /// Experiment of the test windows.
        test_experiment: Experiment,
        /// Features of the test windows.
        test_features: usize,
    },
    /// Truth and predictions of unequal lengths.
    #[error("{truth} true labels but {predicted} predictions")]
    LengthMismatch {
        /// Number of true labels.
        truth: usize,
        /// Number of predictions.
        predicted: usize,
    },
    /// A class index outside a confusion matrix.
    #[error("label {truth} or prediction {predicted} outside {n_classes} classes")]
    ClassOutOfRange {
        /// The true class.
        truth: u32,
        /// The predicted class.
        predicted: u32,
        /// Classes of the matrix.
        n_classes: usize,
    },
    /// Two confusion matrices of different sizes were merged.
    #[error("confusion matrices of different sizes")]
    ConfusionSize {
        /// Classes of the matrix merged into.
        expected: usize,
        /// Classes of the other matrix.
        found: usize,
    },
    /// A count is below its minimum; the message names it as the command line does (e.g. `--trees must be
    /// at least 1`).
    #[error("{argument} must be at least {min}")]
    TooSmall {
        /// The argument, e.g. `--trees`.
        argument: &'static str,
        /// The smallest value accepted.
        min: usize,
    },
    /// A value of a list is below its minimum (e.g. `--trees: every tree count must be at least 1`).
    #[error("{argument}: every {what} must be at least {min}")]
    ListTooSmall {
        /// The argument, e.g. `--trees`.
        argument: &'static str,
        /// What one value is, e.g. `tree count`.
        what: &'static str,
        /// The smallest value accepted.
        min: usize,
    },
    /// A grid or measurement setting is unusable (the trade-off sweep, the latency batch).
    #[error("{reason}")]
    InvalidSetting {
        /// What is wrong.
        reason: &'static str,
    },
    /// The two-height print check cannot judge these passes ([`crate::print_check`]).
    #[error("print check: {reason}")]
    PrintCheck {
        /// Why.
        reason: String,
    },
    /// A statistical test cannot be computed on these values.
    #[error("{reason}")]
    Statistics {
        /// Why.
        reason: String,
    },
    /// A folder could not be created or a result file written.
    #[error("{action} {}", path.display())]
    Io {
        /// What was being done: `creating` or `writing`.
        action: &'static str,
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A result could not be turned into JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A figure could not be drawn (by the closure the caller passed in).
    #[error(transparent)]
    Figure(Box<dyn std::error::Error + Send + Sync>),
    /// A slide given to the localiser ([`crate::localise`]) is unusable (no samples, samples and positions of
    /// different lengths, a non-finite value, no travel) or its settings are invalid.
    #[error("localisation: {reason}")]
    Localisation {
        /// What is wrong.
        reason: String,
    },
}

impl TactileError {
    /// A [`Figure`](TactileError::Figure) error from whatever the figure-drawing closure failed with.
    pub fn figure(error: impl std::error::Error + Send + Sync + 'static) -> Self {
        TactileError::Figure(Box::new(error))
    }
}

#[cfg(feature = "research")]
impl TactileError {
    /// An [`Io`](TactileError::Io) error while creating `path`.
    pub(crate) fn creating(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self + '_ {
        move |source| TactileError::Io {
            action: "creating",
            path: path.to_path_buf(),
            source,
        }
    }

    /// An [`Io`](TactileError::Io) error while writing `path`.
    pub(crate) fn writing(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self + '_ {
        move |source| TactileError::Io {
            action: "writing",
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Refuses a forest of no trees: `--trees must be at least 1`, as the command line names it.
pub(crate) fn check_n_trees(n_trees: usize) -> Result<(), TactileError> {
    if n_trees == 0 {
        return Err(TactileError::TooSmall {
            argument: "--trees",
            min: 1,
        });
    }
    Ok(())
}
