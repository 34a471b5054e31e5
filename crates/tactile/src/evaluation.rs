//! The `crackbot tactile eval` flow as one call: train on some recordings, test on others, and return
//! a [`Serialize`] report ([`EvalReport`]) that any front end prints (the CLI's `--json` output is this
//! report, key for key).
//!
//! The flow: the experiment (given, or detected from the labels of all recordings), the labelled windows
//! of both sets ([`PipelineConfig`], checked once), the classifier trained on the training windows and
//! timed, with context features a second forest on the paper's own window features that joins the slide
//! verdicts ([`SlideVote`]), window- and slide-level metrics on the test windows and, for the width
//! experiment, the crack width by regression. Progress of every forest goes to a callback
//! ([`EvalStage`]); nothing is drawn here.

use std::path::PathBuf;
use std::time::Instant;

use crackbot_dsp::WindowConfig;
use crackbot_recording::{collect_recordings, Recording};
use serde::Serialize;

use crate::context::ContextConfig;
use crate::dataset::{choose_experiment, Experiment, PipelineConfig, WindowSet};
use crate::error::check_n_trees;
use crate::eval::{
    test_classifier, test_classifier_with_slide_voters, train_classifier_tuned,
    width_regression_tuned, ClassificationOutcome, ClassifierKind, ForestTuning, WidthOutcome,
};
use crate::model::TactileModel;
use crate::TactileError;

pub use crate::vote::SlideVote;

/// What [`evaluate`] does.
#[derive(Debug, Clone, PartialEq)]
pub struct EvalConfig {
    /// The experiment; `None` detects it from the labels of all recordings.
    pub experiment: Option<Experiment>,
    /// Segmentation, windows, features, normalisation and context of the windows.
    pub pipeline: PipelineConfig,
    /// The classifier.
    pub classifier: ClassifierKind,
    /// Trees of the width regressor (and, by the command line's convention, of the classifier when it
    /// is a forest); at least 1.
    pub n_trees: usize,
    /// Tree settings of the random forests beyond the number of trees.
    pub tuning: ForestTuning,
    /// Seed of the forests.
    pub seed: u64,
    /// Slide verdicts with context features (ignored without).
    pub slide_vote: SlideVote,
}

impl Default for EvalConfig {
    /// The paper's pipeline and random forest (100 trees), seed 1, experiment detected.
    fn default() -> Self {
        EvalConfig {
            experiment: None,
            pipeline: PipelineConfig::default(),
            classifier: ClassifierKind::Forest { n_trees: 100 },
            n_trees: 100,
            tuning: ForestTuning::default(),
            seed: 1,
            slide_vote: SlideVote::Both,
        }
    }
}

/// Which model of the flow a progress report is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EvalStage {
    /// The classifier on the configured windows.
    Classifier,
    /// The forest on the paper's window features that joins the slide verdicts (with context).
    SlideVoter,
    /// The width regressor (width experiment).
    WidthRegressor,
}

/// The outcome of [`evaluate`]; its JSON form is `crackbot tactile eval --json`. Fields are in
/// alphabetical order, as that output has always been.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    /// Class names, in class order.
    pub classes: Vec<String>,
    /// `RF`, `KNN` or `QDA`.
    pub classifier: String,
    /// The context features, when used.
    pub context: Option<ContextConfig>,
    /// `recognition` or `width`.
    pub experiment: String,
    /// Feature name(s) (`RAW`, `MAV`, `RMS`; joined with `+` when several).
    pub feature: String,
    /// The forests' tree settings.
    pub forest_tuning: ForestTuning,
    /// Values per window.
    pub n_features: usize,
    /// `None` or `RecordingMedian`.
    pub normalisation: String,
    /// `none`, `paper` or `robust`.
    pub segmentation: String,
    /// Channel set (`P`, `D1D2D3`, `D1D2D3+P`, `D1D2+P`).
    pub set: String,
    /// Slide-level accuracy.
    pub slide_accuracy: f64,
    /// Slide-level confusion matrix, rows = true classes.
    pub slide_confusion: Vec<Vec<u64>>,
    /// Slide-level weighted precision.
    pub slide_precision: f64,
    /// Slide-level weighted recall.
    pub slide_recall: f64,
    /// Who decided the slide verdicts: `paper`, `context` or `context+paper`.
    pub slide_vote: String,
    /// Width regression: mean absolute error per slide (median of its windows), mm.
    pub slide_width_mae_mm: Option<f64>,
    /// The width experiment: mean absolute error per slide of the width the robot reports (the
    /// slide verdict's class width, `online::WidthEstimate::mm`), from the slide confusion, mm.
    pub slide_width_reported_mae_mm: Option<f64>,
    /// Test recordings.
    pub test_recordings: usize,
    /// Test slides with at least one window.
    pub test_slides: u64,
    /// Test windows.
    pub test_windows: usize,
    /// Training recordings.
    pub train_recordings: usize,
    /// Training time of the classifier (and the slide voter, windows included), seconds.
    pub train_seconds: f64,
    /// Training windows.
    pub train_windows: usize,
    /// Width regression: mean absolute error per window, mm.
    pub width_mae_mm: Option<f64>,
    /// Window length and step.
    pub window: WindowConfig,
    /// Window-level accuracy.
    pub window_accuracy: f64,
    /// Window-level confusion matrix, rows = true classes.
    pub window_confusion: Vec<Vec<u64>>,
    /// Window-level weighted precision.
    pub window_precision: f64,
    /// Window-level weighted recall.
    pub window_recall: f64,
}

/// Reads the recordings named by `train` and `test` (files or folders, see [`collect_recordings`]) and
/// runs [`evaluate_recordings`].
pub fn evaluate(
    config: &EvalConfig,
    train: &[PathBuf],
    test: &[PathBuf],
    progress: impl FnMut(EvalStage, usize, usize) + Send,
) -> Result<EvalReport, TactileError> {
    check_n_trees(config.n_trees)?;
    let train = collect_recordings(train)?;
    let test = collect_recordings(test)?;
    evaluate_checked(config, &train, &test, progress)
}

/// Trains on `train`, tests on `test` (see the [module docs](self)). `progress(stage, done, total)` is
/// called after each tree of each forest.
pub fn evaluate_recordings(
    config: &EvalConfig,
    train: &[(PathBuf, Recording)],
    test: &[(PathBuf, Recording)],
    progress: impl FnMut(EvalStage, usize, usize) + Send,
) -> Result<EvalReport, TactileError> {
    check_n_trees(config.n_trees)?;
    evaluate_checked(config, train, test, progress)
}

/// [`evaluate_recordings`] with the number of trees checked.
fn evaluate_checked(
    config: &EvalConfig,
    train: &[(PathBuf, Recording)],
    test: &[(PathBuf, Recording)],
    mut progress: impl FnMut(EvalStage, usize, usize) + Send,
) -> Result<EvalReport, TactileError> {
    let experiment = choose_experiment(config.experiment, train, test)?;
    let pipeline = config.pipeline.check()?;
    let train_set = pipeline.build_windows(train, experiment)?;
    let test_set = pipeline.build_windows(test, experiment)?;
    let (kind, tuning, seed) = (config.classifier, config.tuning, config.seed);
    let started = Instant::now();
    let model = train_classifier_tuned(&train_set, kind, tuning, seed, &mut |done, total| {
        progress(EvalStage::Classifier, done, total);
    })?;
    // With context, a forest on the paper's own window features (same segmentation and windows,
    // so the same slides) joins the slide verdicts.
    let voter = if config.pipeline.context.is_some() && config.slide_vote == SlideVote::Both {
        let plain = pipeline.without_context();
        let vote_train = plain.build_windows(train, experiment)?;
        let vote_test = plain.build_windows(test, experiment)?;
        let vote_model =
            train_classifier_tuned(&vote_train, kind, tuning, seed, &mut |done, total| {
                progress(EvalStage::SlideVoter, done, total);
            })?;
        Some((vote_model, vote_test))
    } else {
        None
    };
    let train_seconds = started.elapsed().as_secs_f64();
    let outcome = match &voter {
        Some((vote_model, vote_test)) => test_classifier_with_slide_voters(
            model.as_ref(),
            &test_set,
            &[(vote_model.as_ref(), vote_test)],
        )?,
        None => test_classifier(model.as_ref(), &test_set)?,
    };
    let width = match experiment {
        Experiment::Width => Some(width_regression_tuned(
            &train_set,
            &test_set,
            config.n_trees,
            tuning,
            seed,
            &mut |done, total| progress(EvalStage::WidthRegressor, done, total),
        )?),
        Experiment::Recognition => None,
    };
    let p = &config.pipeline;
    let slide_vote = if voter.is_some() {
        "context+paper"
    } else if p.context.is_some() {
        "context"
    } else {
        "paper"
    };
    Ok(report(
        p,
        experiment,
        &outcome,
        width.as_ref(),
        ReportFacts {
            classes: experiment
                .class_names()
                .iter()
                .map(std::string::ToString::to_string)
                .collect(),
            classifier: kind.name(),
            forest_tuning: tuning,
            n_features: train_set.n_features,
            slide_vote,
            test_recordings: test.len(),
            test_windows: test_set.n_rows(),
            train_recordings: train.len(),
            train_seconds,
            train_windows: train_set.n_rows(),
        },
    ))
}

/// Evaluates a deployed model ([`TactileModel`]) on the recordings named by `test`, without
/// training: the same report as [`evaluate`], the training fields taken from the model's header
/// (`train_recordings`, `train_windows`, `train_seconds`).
pub fn evaluate_model(model: &TactileModel, test: &[PathBuf]) -> Result<EvalReport, TactileError> {
    let test = collect_recordings(test)?;
    evaluate_model_recordings(model, &test)
}

/// [`evaluate_model`] on recordings already read.
pub fn evaluate_model_recordings(
    model: &TactileModel,
    test: &[(PathBuf, Recording)],
) -> Result<EvalReport, TactileError> {
    let experiment = crate::dataset::detect_experiment(test).or_else(|e| {
        // Labels of both experiments (0, 1, 2 only) are read as the model's.
        match e {
            TactileError::Experiment(crackbot_recording::ExperimentError::Ambiguous { .. }) => {
                Ok(model.experiment())
            }
            other => Err(other),
        }
    })?;
    if experiment != model.experiment() {
        return Err(TactileError::ExperimentMismatch {
            model: model.experiment().name(),
            data: experiment.name(),
        });
    }
    let pipeline = model.pipeline()?;
    let test_set = pipeline.build_windows(test, experiment)?;
    let vote_test = pipeline.without_context().build_windows(test, experiment)?;
    let voters: &[(&(dyn crackbot_forest::Classifier + Send + Sync), &WindowSet)] =
        match model.header.slide_vote {
            SlideVote::Both => &[(&model.window_forest, &vote_test)],
            SlideVote::Context => &[],
        };
    let outcome = test_classifier_with_slide_voters(&model.context_forest, &test_set, voters)?;
    let width = match &model.width {
        Some(w) => Some(crate::eval::width_outcome(w, &test_set)?),
        None => None,
    };
    let h = &model.header;
    let p = &h.pipeline;
    Ok(report(
        p,
        experiment,
        &outcome,
        width.as_ref(),
        ReportFacts {
            classes: h.classes.clone(),
            classifier: "RF",
            forest_tuning: ForestTuning {
                max_features_fraction: None,
                max_depth: h.training.config.max_depth,
                min_samples_leaf: None,
            },
            n_features: test_set.n_features,
            slide_vote: h.slide_vote.name(),
            test_recordings: test.len(),
            test_windows: test_set.n_rows(),
            train_recordings: h.training.recordings.len(),
            train_seconds: h.training.seconds,
            train_windows: h.training.windows,
        },
    ))
}

/// What a report says beyond the pipeline and the outcome.
struct ReportFacts {
    classes: Vec<String>,
    classifier: &'static str,
    forest_tuning: ForestTuning,
    n_features: usize,
    slide_vote: &'static str,
    test_recordings: usize,
    test_windows: usize,
    train_recordings: usize,
    train_seconds: f64,
    train_windows: usize,
}

/// The report of `outcome` (and `width`) under pipeline `p`: one place for the metric fields of
/// [`evaluate`] and [`evaluate_model`].
fn report(
    p: &PipelineConfig,
    experiment: Experiment,
    outcome: &ClassificationOutcome,
    width: Option<&WidthOutcome>,
    facts: ReportFacts,
) -> EvalReport {
    let (w, s) = (&outcome.windows, &outcome.slides);
    EvalReport {
        classes: facts.classes,
        classifier: facts.classifier.to_string(),
        context: p.context.clone(),
        experiment: experiment.name().to_string(),
        feature: p.spec.feature_name(),
        forest_tuning: facts.forest_tuning,
        n_features: facts.n_features,
        normalisation: format!("{:?}", p.normalisation),
        segmentation: p.segmentation.name().to_string(),
        set: p.spec.set.name().to_string(),
        slide_accuracy: s.accuracy(),
        slide_confusion: s.rows(),
        slide_precision: s.weighted_precision(),
        slide_recall: s.weighted_recall(),
        slide_vote: facts.slide_vote.to_string(),
        slide_width_mae_mm: width.map(|x| x.slide_mae_mm),
        slide_width_reported_mae_mm: reported_width_mae(experiment, &s.rows()),
        test_recordings: facts.test_recordings,
        test_slides: s.total(),
        test_windows: facts.test_windows,
        train_recordings: facts.train_recordings,
        train_seconds: facts.train_seconds,
        train_windows: facts.train_windows,
        width_mae_mm: width.map(|x| x.window_mae_mm),
        window: p.window,
        window_accuracy: w.accuracy(),
        window_confusion: w.rows(),
        window_precision: w.weighted_precision(),
        window_recall: w.weighted_recall(),
    }
}

/// The mean absolute error of the class widths a slide confusion (rows = true classes) puts on
/// the slides, for the width experiment (its labels are widths in mm); `None` for another
/// experiment or no slide.
pub fn reported_width_mae(experiment: Experiment, confusion: &[Vec<u64>]) -> Option<f64> {
    if experiment != Experiment::Width {
        return None;
    }
    let widths = experiment.labels();
    let (mut error, mut slides) = (0.0, 0u64);
    for (row, truth) in confusion.iter().zip(widths) {
        for (count, said) in row.iter().zip(widths) {
            error += *count as f64 * (said - truth).abs();
            slides += count;
        }
    }
    (slides > 0).then(|| error / slides as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_trees_are_refused_before_anything_is_read() {
        let config = EvalConfig {
            n_trees: 0,
            ..EvalConfig::default()
        };
        let missing = [PathBuf::from("/nonexistent/recordings")];
        let err = evaluate(&config, &missing, &missing, |_, _, _| {}).unwrap_err();
        assert_eq!(err.to_string(), "--trees must be at least 1");
    }

    #[test]
    fn reported_width_error_weighs_each_slide_by_how_far_its_class_is() {
        // Widths 0, 1, 2, 5, 8, 10 mm: two 1 mm slides called 10 mm, one 5 mm slide called 2 mm,
        // seven right.
        let mut confusion = vec![vec![0u64; 6]; 6];
        confusion[1][1] = 3;
        confusion[1][5] = 2;
        confusion[3][2] = 1;
        confusion[0][0] = 4;
        let mae = reported_width_mae(Experiment::Width, &confusion).unwrap();
        assert!((mae - (2.0 * 9.0 + 3.0) / 10.0).abs() < 1e-12, "{mae}");
        assert_eq!(
            reported_width_mae(Experiment::Width, &vec![vec![0; 6]; 6]),
            None
        );
        assert_eq!(
            reported_width_mae(Experiment::Recognition, &confusion),
            None
        );
    }
}
