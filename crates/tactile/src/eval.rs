//! Training a classifier on one [`WindowSet`] and testing it on another: window-level and
//! slide-level confusion matrices, and crack width by regression.

use crackbot_forest::{
    Classifier, Dataset, ForestParams, Knn, KnnParams, MaxFeatures, Qda, QdaParams, RandomForest,
    RandomForestRegressor, RegressionDataset,
};
use rayon::prelude::*;
use serde::Serialize;

use crate::dataset::WindowSet;
use crate::metrics::{mean_absolute_error, ConfusionMatrix};
use crate::TactileError;

/// The classifiers the paper compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ClassifierKind {
    /// Random forest (100 trees in the paper).
    Forest {
        /// Number of trees.
        n_trees: usize,
    },
    /// k-nearest neighbours, k = 5.
    Knn,
    /// Quadratic discriminant analysis (regularised).
    Qda,
}

impl ClassifierKind {
    /// Short name for tables (`RF`, `KNN`, `QDA`).
    pub fn name(&self) -> &'static str {
        match self {
            ClassifierKind::Forest { .. } => "RF",
            ClassifierKind::Knn => "KNN",
            ClassifierKind::Qda => "QDA",
        }
    }
}

/// Tree settings of the random forests beyond the number of trees; the default is
/// scikit-learn's (`max_features = sqrt` for classification, unlimited depth, leaves of 1).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ForestTuning {
    /// Candidate features per split as a fraction of the features (`None`: square root).
    pub max_features_fraction: Option<f64>,
    /// Maximum tree depth (`None`: unlimited).
    pub max_depth: Option<usize>,
    /// Minimum samples per leaf (`None`: 1).
    pub min_samples_leaf: Option<usize>,
}

impl ForestTuning {
    /// Applies the settings to `params` (the classifier's or the regressor's defaults).
    pub fn apply(&self, mut params: ForestParams) -> ForestParams {
        if let Some(f) = self.max_features_fraction {
            params = params.max_features(MaxFeatures::Fraction(f));
        }
        if let Some(d) = self.max_depth {
            params = params.max_depth(Some(d));
        }
        if let Some(n) = self.min_samples_leaf {
            params = params.min_samples_leaf(n);
        }
        params
    }
}

/// Reports the training of a random forest: `(trees done, trees in all)` after each tree, one call at a
/// time, in order (see [`RandomForest::fit_with_progress`]). KNN and QDA report nothing.
pub use crackbot_forest::TrainProgress;

/// Trains `kind` on every window of `train`, reporting no progress.
pub fn train_classifier(
    train: &WindowSet,
    kind: ClassifierKind,
    seed: u64,
) -> Result<Box<dyn Classifier + Send + Sync>, TactileError> {
    train_classifier_tuned(train, kind, ForestTuning::default(), seed, &mut |_, _| {})
}

/// [`train_classifier`] with forest settings (ignored by KNN and QDA), reporting a forest's progress
/// to `progress`.
pub fn train_classifier_tuned(
    train: &WindowSet,
    kind: ClassifierKind,
    tuning: ForestTuning,
    seed: u64,
    progress: TrainProgress<'_>,
) -> Result<Box<dyn Classifier + Send + Sync>, TactileError> {
    let data = Dataset::with_classes(
        train.x.clone(),
        train.n_features,
        train.y.clone(),
        train.experiment.n_classes(),
    )?;
    Ok(match kind {
        ClassifierKind::Forest { n_trees } => {
            let params = tuning.apply(ForestParams::classifier().n_trees(n_trees).seed(seed));
            Box::new(RandomForest::fit_with_progress(&data, &params, progress)?)
        }
        ClassifierKind::Knn => Box::new(Knn::fit(&data, KnnParams::default())?),
        ClassifierKind::Qda => Box::new(Qda::fit(&data, QdaParams::default())?),
    })
}

/// Window-level and slide-level results of a classifier on a test set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassificationOutcome {
    /// One count per window.
    pub windows: ConfusionMatrix,
    /// One count per slide: the slide's verdict is the class of highest mean probability over
    /// its windows (slides without windows are left out).
    pub slides: ConfusionMatrix,
}

/// Tests `model` on `test`: window verdicts and slide verdicts both from `model`.
pub fn test_classifier(
    model: &(dyn Classifier + Send + Sync),
    test: &WindowSet,
) -> Result<ClassificationOutcome, TactileError> {
    let proba = window_probabilities(model, test)?;
    outcome(test, &proba, &[&proba])
}

/// Tests `model` on `test` for window verdicts, and lets `voters` join the slide verdicts: a
/// slide's verdict is the class of highest summed mean probability over `model` and every voter,
/// each voter classifying its own windows (`(classifier, its window set)`). Every voter's set must
/// cut the same recordings into the same slides and windows as `test` (same pipeline, other
/// features), otherwise an error names the first slide that differs.
///
/// Why: windows with causal context ([`crate::context`]) are right far more often than the
/// paper's windows, but the windows of one slide then share their errors; the paper's windows are
/// wrong more often, but independently, so their mean is a robust slide verdict. Summing both
/// keeps each one's strength (see the `crate::context` docs for the figures).
pub fn test_classifier_with_slide_voters(
    model: &(dyn Classifier + Send + Sync),
    test: &WindowSet,
    voters: &[(&(dyn Classifier + Send + Sync), &WindowSet)],
) -> Result<ClassificationOutcome, TactileError> {
    let own = window_probabilities(model, test)?;
    let mut all = vec![own];
    for (i, (voter, set)) in voters.iter().enumerate() {
        if set.slides.len() != test.slides.len() || set.experiment != test.experiment {
            return Err(TactileError::SlideVoter {
                voter: i,
                detail: format!(
                    "{} slides of the {} experiment, the test set has {} of the {}",
                    set.slides.len(),
                    set.experiment.name(),
                    test.slides.len(),
                    test.experiment.name()
                ),
            });
        }
        if let Some((j, (a, b))) = set
            .slides
            .iter()
            .zip(&test.slides)
            .enumerate()
            .find(|(_, (a, b))| a.windows != b.windows || a.class != b.class)
        {
            return Err(TactileError::SlideVoter {
                voter: i,
                detail: format!(
                    "slide {j} (recording {}, slide {}) has windows {:?}, the test set {:?} (recording {}, slide {})",
                    a.recording, a.slide, a.windows, b.windows, b.recording, b.slide
                ),
            });
        }
        all.push(window_probabilities(*voter, set)?);
    }
    let refs: Vec<&[f32]> = all.iter().map(std::vec::Vec::as_slice).collect();
    outcome(test, &all[0], &refs)
}

/// Class probabilities of every window of `set` (row-major, `n_rows × n_classes`).
fn window_probabilities(
    model: &(dyn Classifier + Send + Sync),
    set: &WindowSet,
) -> Result<Vec<f32>, TactileError> {
    let k = set.experiment.n_classes();
    if model.n_classes() != k || model.n_features() != set.n_features {
        return Err(TactileError::ModelMismatch {
            model_classes: model.n_classes(),
            model_features: model.n_features(),
            set_classes: k,
            set_features: set.n_features,
        });
    }
    let mut proba = vec![0f32; set.n_rows() * k];
    proba
        .par_chunks_mut(k)
        .enumerate()
        .for_each(|(i, out)| model.predict_proba_into(set.row(i), out));
    Ok(proba)
}

/// Window confusion from `window_proba`; slide confusion from the summed per-slide mean of every
/// table in `slide_proba` (all `n_rows × n_classes`, rows aligned with `test`).
fn outcome(
    test: &WindowSet,
    window_proba: &[f32],
    slide_proba: &[&[f32]],
) -> Result<ClassificationOutcome, TactileError> {
    let k = test.experiment.n_classes();
    let mut windows = ConfusionMatrix::new(k);
    let mut slides = ConfusionMatrix::new(k);
    for slide in &test.slides {
        if slide.windows.is_empty() {
            continue;
        }
        for i in slide.windows.clone() {
            windows.add(
                test.y[i],
                crackbot_forest::argmax(&window_proba[i * k..(i + 1) * k]),
            )?;
        }
        let r = slide.windows.start * k..slide.windows.end * k;
        let tables: Vec<&[f32]> = slide_proba.iter().map(|p| &p[r.clone()]).collect();
        let mean = crate::vote::slide_means(&tables, slide.windows.len(), k);
        let mean32: Vec<f32> = mean.iter().map(|&m| m as f32).collect();
        slides.add(slide.class, crackbot_forest::argmax(&mean32))?;
    }
    Ok(ClassificationOutcome { windows, slides })
}

/// Crack width estimated by a random-forest regressor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WidthOutcome {
    /// Mean absolute error per window, mm.
    pub window_mae_mm: f64,
    /// Mean absolute error per slide (median of its window estimates), mm.
    pub slide_mae_mm: f64,
}

/// Trains a width regressor on `train` (labels in mm) and measures it on `test`, reporting no
/// progress.
pub fn width_regression(
    train: &WindowSet,
    test: &WindowSet,
    n_trees: usize,
    seed: u64,
) -> Result<WidthOutcome, TactileError> {
    width_regression_tuned(
        train,
        test,
        n_trees,
        ForestTuning::default(),
        seed,
        &mut |_, _| {},
    )
}

/// [`width_regression`] with forest settings (a `max_features` fraction replaces the regressor's
/// default of every feature), reporting the regressor's progress to `progress`.
pub fn width_regression_tuned(
    train: &WindowSet,
    test: &WindowSet,
    n_trees: usize,
    tuning: ForestTuning,
    seed: u64,
    progress: TrainProgress<'_>,
) -> Result<WidthOutcome, TactileError> {
    let y: Vec<f32> = train.label.iter().map(|&l| l as f32).collect();
    let data = RegressionDataset::new(train.x.clone(), train.n_features, y)?;
    let params = tuning.apply(ForestParams::regressor().n_trees(n_trees).seed(seed));
    let model = RandomForestRegressor::fit_with_progress(&data, &params, progress)?;
    width_outcome(&model, test)
}

/// Measures a trained width regressor on `test` (labels in mm): window and slide (median) errors.
pub fn width_outcome(
    model: &RandomForestRegressor,
    test: &WindowSet,
) -> Result<WidthOutcome, TactileError> {
    let mut estimates = vec![0f32; test.n_rows()];
    model.predict_batch(&test.x, test.n_features, &mut estimates)?;
    let window_est: Vec<f64> = estimates.iter().map(|&e| f64::from(e)).collect();
    let window_mae_mm = mean_absolute_error(&test.label, &window_est);
    let mut slide_truth = Vec::new();
    let mut slide_est = Vec::new();
    for slide in test.slides.iter().filter(|s| !s.windows.is_empty()) {
        let mut v: Vec<f64> = window_est[slide.windows.clone()].to_vec();
        v.sort_by(f64::total_cmp);
        let mid = v.len() / 2;
        let median = if v.len() % 2 == 1 {
            v[mid]
        } else {
            (v[mid - 1] + v[mid]) / 2.0
        };
        slide_truth.push(slide.label);
        slide_est.push(median);
    }
    Ok(WidthOutcome {
        window_mae_mm,
        slide_mae_mm: mean_absolute_error(&slide_truth, &slide_est),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuning_overrides_only_what_it_names() {
        let base = ForestParams::classifier();
        assert_eq!(ForestTuning::default().apply(base.clone()), base);
        let t = ForestTuning {
            max_features_fraction: Some(0.5),
            max_depth: Some(12),
            min_samples_leaf: Some(4),
        };
        let p = t.apply(base);
        assert_eq!(p.max_features, MaxFeatures::Fraction(0.5));
        assert_eq!(p.max_depth, Some(12));
        assert_eq!(p.min_samples_leaf, 4);
        assert_eq!(p.n_trees, 100);
    }

    /// Reads row `[p0, p1, p2, p3]` as the class probabilities (recognition: 4 classes).
    struct Echo;
    impl Classifier for Echo {
        fn n_classes(&self) -> usize {
            4
        }
        fn n_features(&self) -> usize {
            4
        }
        fn predict_proba_into(&self, x: &[f32], out: &mut [f32]) {
            out.copy_from_slice(&x[..4]);
        }
    }

    fn set(rows: &[[f32; 4]], slides: &[(u32, std::ops::Range<usize>)]) -> WindowSet {
        use crate::dataset::{Experiment, SlideRef};
        let mut y = vec![0; rows.len()];
        for (class, r) in slides {
            y[r.clone()].fill(*class);
        }
        WindowSet {
            experiment: Experiment::Recognition,
            x: rows.iter().flatten().copied().collect(),
            n_features: 4,
            label: y.iter().map(|&c| f64::from(c)).collect(),
            y,
            slides: slides
                .iter()
                .enumerate()
                .map(|(i, (class, r))| SlideRef {
                    recording: 0,
                    slide: i as u32 + 1,
                    class: *class,
                    label: f64::from(*class),
                    windows: r.clone(),
                })
                .collect(),
            sources: vec![],
        }
    }

    #[test]
    fn slide_voters_join_the_slide_verdict_but_not_the_windows() {
        // Slide 1 (crack): the context model is right on 2 of 3 windows, but its one wrong window
        // is confidently "bump", so its slide mean says bump.
        let ctx = set(
            &[
                [0.0, 0.6, 0.4, 0.0],
                [0.0, 0.6, 0.4, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
            &[(1, 0..3)],
        );
        let alone = test_classifier(&Echo, &ctx).unwrap();
        assert_eq!(alone.windows.accuracy(), 2.0 / 3.0);
        assert_eq!(alone.slides.accuracy(), 0.0);
        // The paper-feature voter is right on average (wrong on one window).
        let paper = set(
            &[
                [0.0, 0.9, 0.1, 0.0],
                [0.4, 0.3, 0.3, 0.0],
                [0.0, 0.9, 0.1, 0.0],
            ],
            &[(1, 0..3)],
        );
        let both = test_classifier_with_slide_voters(&Echo, &ctx, &[(&Echo, &paper)]).unwrap();
        assert_eq!(both.windows, alone.windows, "windows stay the model's own");
        assert_eq!(both.slides.accuracy(), 1.0);
        // A voter cut into other slides is refused, naming the slide.
        let shifted = set(
            &[
                [0.0, 0.9, 0.1, 0.0],
                [0.4, 0.3, 0.3, 0.0],
                [0.0, 0.9, 0.1, 0.0],
            ],
            &[(1, 0..2), (1, 2..3)],
        );
        let err = test_classifier_with_slide_voters(&Echo, &ctx, &[(&Echo, &shifted)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("2 slides"), "{err}");
        let moved = set(
            &[
                [0.0, 0.9, 0.1, 0.0],
                [0.4, 0.3, 0.3, 0.0],
                [0.0, 0.9, 0.1, 0.0],
            ],
            &[(2, 0..3)],
        );
        let err = test_classifier_with_slide_voters(&Echo, &ctx, &[(&Echo, &moved)])
            .unwrap_err()
            .to_string();
        assert!(err.contains("slide 0"), "{err}");
    }
}
