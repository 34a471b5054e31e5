//! Hyper-parameters of forest training.

use crate::error::{ForestError, Result};

/// How many features are drawn as split candidates at each node (scikit-learn's `max_features`).
///
/// Features are sampled per *split* (as scikit-learn does), not once per tree (as linfa does). Features that
/// are constant within the node do not count towards the number, so a node is only made a leaf for lack of
/// candidates when every feature is constant in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MaxFeatures {
    /// `max(1, floor(sqrt(n_features)))` — scikit-learn's classifier default.
    Sqrt,
    /// `max(1, floor(log2(n_features)))`.
    Log2,
    /// Every feature — scikit-learn's regressor default (plain bagging).
    All,
    /// A fixed number (clamped to `n_features`; must be at least 1).
    Count(usize),
    /// `max(1, floor(fraction · n_features))`, fraction in `(0, 1]`.
    Fraction(f64),
}

impl MaxFeatures {
    /// Number of candidate features for `n_features` features.
    pub fn resolve(&self, n_features: usize) -> Result<usize> {
        let n = n_features.max(1);
        let m = match *self {
            MaxFeatures::Sqrt => (n as f64).sqrt().floor() as usize,
            MaxFeatures::Log2 => (n as f64).log2().floor() as usize,
            MaxFeatures::All => n,
            MaxFeatures::Count(c) => {
                if c == 0 {
                    return Err(ForestError::InvalidParams("max_features Count(0)".into()));
                }
                c
            }
            MaxFeatures::Fraction(f) => {
                if !(f > 0.0 && f <= 1.0) {
                    return Err(ForestError::InvalidParams(format!(
                        "max_features fraction {f} not in (0, 1]"
                    )));
                }
                (f * n as f64).floor() as usize
            }
        };
        Ok(m.clamp(1, n))
    }
}

/// Parameters of [`RandomForest::fit`](crate::RandomForest::fit) and
/// [`RandomForestRegressor::fit`](crate::RandomForestRegressor::fit).
///
/// The defaults ([`ForestParams::classifier`]) are scikit-learn's `RandomForestClassifier` defaults:
/// 100 fully grown trees, bootstrap, Gini, `max_features = sqrt`, `min_samples_leaf = 1`.
#[derive(Debug, Clone, PartialEq)]
pub struct ForestParams {
    /// Number of trees (≥ 1).
    pub n_trees: usize,
    /// Maximum depth (root = depth 0); `None` grows trees until leaves are pure or cannot be split.
    pub max_depth: Option<usize>,
    /// A node with fewer (distinct bootstrap) samples than this is a leaf (≥ 2).
    pub min_samples_split: usize,
    /// Each child must keep at least this many distinct samples (≥ 1). As in scikit-learn, bootstrap
    /// duplicates count once here; they count fully as weights in the criterion and the leaf values.
    pub min_samples_leaf: usize,
    /// Candidate features per split.
    pub max_features: MaxFeatures,
    /// Draw `n_rows` rows with replacement per tree (otherwise every tree sees every row once).
    pub bootstrap: bool,
    /// Seed; tree `i` uses a ChaCha8 stream derived from `(seed, i)`, so a model depends only on the data and
    /// these parameters, never on the number of threads.
    pub seed: u64,
    /// Threads for training: `None` uses rayon's global pool, `Some(n)` a private pool of `n` threads.
    pub n_threads: Option<usize>,
    /// Report no progress: the callback of
    /// [`RandomForest::fit_with_progress`](crate::RandomForest::fit_with_progress) is not called. (This crate
    /// draws nothing itself; a binary draws a progress bar from the callback.)
    pub quiet: bool,
}

impl ForestParams {
    /// scikit-learn `RandomForestClassifier` defaults (100 trees, `max_features = sqrt`), seed 0.
    pub fn classifier() -> Self {
        Self {
            n_trees: 100,
            max_depth: None,
            min_samples_split: 2,
            min_samples_leaf: 1,
            max_features: MaxFeatures::Sqrt,
            bootstrap: true,
            seed: 0,
            n_threads: None,
            quiet: false,
        }
    }

    /// scikit-learn `RandomForestRegressor` defaults (100 trees, every feature at each split), seed 0.
    pub fn regressor() -> Self {
        Self {
            max_features: MaxFeatures::All,
            ..Self::classifier()
        }
    }

    /// Sets the number of trees.
    pub fn n_trees(mut self, n: usize) -> Self {
        self.n_trees = n;
        self
    }
    /// Sets the maximum depth.
    pub fn max_depth(mut self, d: Option<usize>) -> Self {
        self.max_depth = d;
        self
    }
    /// Sets `min_samples_leaf`.
    pub fn min_samples_leaf(mut self, n: usize) -> Self {
        self.min_samples_leaf = n;
        self
    }
    /// Sets `min_samples_split`.
    pub fn min_samples_split(mut self, n: usize) -> Self {
        self.min_samples_split = n;
        self
    }
    /// Sets `max_features`.
    pub fn max_features(mut self, m: MaxFeatures) -> Self {
        self.max_features = m;
        self
    }
    /// Sets bootstrap on or off.
    pub fn bootstrap(mut self, b: bool) -> Self {
        self.bootstrap = b;
        self
    }
    /// Sets the seed.
    pub fn seed(mut self, s: u64) -> Self {
        self.seed = s;
        self
    }
    /// Sets the number of training threads.
    pub fn n_threads(mut self, n: Option<usize>) -> Self {
        self.n_threads = n;
        self
    }
    /// Turns the progress reports off (or on).
    pub fn quiet(mut self, q: bool) -> Self {
        self.quiet = q;
        self
    }

    /// Checks ranges.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(ForestError::InvalidParams(m));
        if self.n_trees == 0 || self.n_trees > 1_000_000 {
            return bad(format!("n_trees {} not in 1..=1000000", self.n_trees));
        }
        if self.max_depth == Some(0) {
            return bad("max_depth must be at least 1 (or None)".into());
        }
        if self.min_samples_leaf == 0 {
            return bad("min_samples_leaf must be at least 1".into());
        }
        if self.min_samples_split < 2 {
            return bad("min_samples_split must be at least 2".into());
        }
        if self.n_threads == Some(0) {
            return bad("n_threads must be at least 1 (or None)".into());
        }
        self.max_features.resolve(1)?;
        Ok(())
    }
}

impl Default for ForestParams {
    fn default() -> Self {
        Self::classifier()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_features_resolution() {
        assert_eq!(MaxFeatures::Sqrt.resolve(3).unwrap(), 1);
        assert_eq!(MaxFeatures::Sqrt.resolve(4).unwrap(), 2);
        assert_eq!(MaxFeatures::Log2.resolve(1).unwrap(), 1);
        assert_eq!(MaxFeatures::All.resolve(3).unwrap(), 3);
        assert_eq!(MaxFeatures::Count(9).resolve(3).unwrap(), 3);
        assert_eq!(MaxFeatures::Fraction(0.5).resolve(4).unwrap(), 2);
        assert!(MaxFeatures::Fraction(f64::NAN).resolve(4).is_err());
        assert!(MaxFeatures::Count(0).resolve(4).is_err());
    }

    #[test]
    fn params_validation() {
        assert!(ForestParams::default().validate().is_ok());
        assert!(ForestParams::default().n_trees(0).validate().is_err());
        assert!(ForestParams::default()
            .min_samples_leaf(0)
            .validate()
            .is_err());
        assert!(ForestParams::default()
            .min_samples_split(1)
            .validate()
            .is_err());
        assert!(ForestParams::default()
            .max_depth(Some(0))
            .validate()
            .is_err());
        assert!(ForestParams::default()
            .n_threads(Some(0))
            .validate()
            .is_err());
        assert_eq!(ForestParams::regressor().max_features, MaxFeatures::All);
    }
}
