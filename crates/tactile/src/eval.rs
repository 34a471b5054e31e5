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

fn forest_error(e: crackbot_forest::ForestError) -> TactileError {
    TactileError::Invalid(e.to_string())
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

/// Trains `kind` on every window of `train`.
pub fn train_classifier(
    train: &WindowSet,
    kind: ClassifierKind,
    seed: u64,
    quiet: bool,
) -> Result<Box<dyn Classifier + Send + Sync>, TactileError> {
    train_classifier_tuned(train, kind, ForestTuning::default(), seed, quiet)
}

/// [`train_classifier`] with forest settings (ignored by KNN and QDA).
pub fn train_classifier_tuned(
    train: &WindowSet,
    kind: ClassifierKind,
    tuning: ForestTuning,
    seed: u64,
    quiet: bool,
) -> Result<Box<dyn Classifier + Send + Sync>, TactileError> {
    let data = Dataset::with_classes(
        train.x.clone(),
        train.n_features,
        train.y.clone(),
        train.experiment.n_classes(),
    )
    .map_err(forest_error)?;
    Ok(match kind {
        ClassifierKind::Forest { n_trees } => {
            let params = tuning.apply(
                ForestParams::classifier()
                    .n_trees(n_trees)
                    .seed(seed)
                    .quiet(quiet),
            );
            Box::new(RandomForest::fit(&data, &params).map_err(forest_error)?)
        }
        ClassifierKind::Knn => {
            Box::new(Knn::fit(&data, KnnParams::default()).map_err(forest_error)?)
        }
        ClassifierKind::Qda => {
            Box::new(Qda::fit(&data, QdaParams::default()).map_err(forest_error)?)
        }
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

/// Tests `model` on `test`.
pub fn test_classifier(
    model: &(dyn Classifier + Send + Sync),
    test: &WindowSet,
) -> Result<ClassificationOutcome, TactileError> {
    let k = test.experiment.n_classes();
    if model.n_classes() != k || model.n_features() != test.n_features {
        return Err(TactileError::Invalid(format!(
            "the model has {} classes and {} features, the test set {} and {}",
            model.n_classes(),
            model.n_features(),
            k,
            test.n_features
        )));
    }
    let mut proba = vec![0f32; test.n_rows() * k];
    proba
        .par_chunks_mut(k)
        .enumerate()
        .for_each(|(i, out)| model.predict_proba_into(test.row(i), out));
    let mut windows = ConfusionMatrix::new(k);
    let mut slides = ConfusionMatrix::new(k);
    for slide in &test.slides {
        if slide.windows.is_empty() {
            continue;
        }
        let mut mean = vec![0f64; k];
        for i in slide.windows.clone() {
            let p = &proba[i * k..(i + 1) * k];
            windows.add(test.y[i], crackbot_forest::argmax(p))?;
            for (m, &v) in mean.iter_mut().zip(p) {
                *m += f64::from(v);
            }
        }
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

/// Trains a width regressor on `train` (labels in mm) and measures it on `test`.
pub fn width_regression(
    train: &WindowSet,
    test: &WindowSet,
    n_trees: usize,
    seed: u64,
    quiet: bool,
) -> Result<WidthOutcome, TactileError> {
    width_regression_tuned(train, test, n_trees, ForestTuning::default(), seed, quiet)
}

/// [`width_regression`] with forest settings (a `max_features` fraction replaces the regressor's
/// default of every feature).
pub fn width_regression_tuned(
    train: &WindowSet,
    test: &WindowSet,
    n_trees: usize,
    tuning: ForestTuning,
    seed: u64,
    quiet: bool,
) -> Result<WidthOutcome, TactileError> {
    let y: Vec<f32> = train.label.iter().map(|&l| l as f32).collect();
    let data =
        RegressionDataset::new(train.x.clone(), train.n_features, y).map_err(forest_error)?;
    let params = tuning.apply(
        ForestParams::regressor()
            .n_trees(n_trees)
            .seed(seed)
            .quiet(quiet),
    );
    let model = RandomForestRegressor::fit(&data, &params).map_err(forest_error)?;
    let mut estimates = vec![0f32; test.n_rows()];
    model
        .predict_batch(&test.x, test.n_features, &mut estimates)
        .map_err(forest_error)?;
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
}
