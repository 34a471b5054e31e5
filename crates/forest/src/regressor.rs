//! The random-forest regressor (e.g. crack width in mm): variance-reduction splits, mean leaves.

use std::path::Path;

use crate::data::RegressionDataset;
use crate::error::{ForestError, Result};
use crate::flat::{BlockScratch, FlatTrees, Node, BLOCK_ROWS};
use crate::format::{self, Kind, Parts};
use crate::params::ForestParams;
use crate::train::{train, Mse};

/// A trained random-forest regressor in the flat layout (leaf values = the weighted mean target of the
/// leaf's bootstrap sample). The prediction is the mean over trees.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomForestRegressor {
    pub(crate) trees: FlatTrees,
    importances: Option<Vec<f64>>,
}

impl RandomForestRegressor {
    /// Trains on `data`; use [`ForestParams::regressor`] for scikit-learn's regressor defaults.
    pub fn fit(data: &RegressionDataset, params: &ForestParams) -> Result<Self> {
        Self::fit_with_progress(data, params, |_, _| {})
    }

    /// [`fit`](Self::fit), reporting progress as
    /// [`RandomForest::fit_with_progress`](crate::RandomForest::fit_with_progress) does.
    pub fn fit_with_progress(
        data: &RegressionDataset,
        params: &ForestParams,
        mut progress: impl FnMut(usize, usize) + Send,
    ) -> Result<Self> {
        let task = Mse { y: data.y() };
        let (trees, importances) =
            train(&task, data.x(), data.n_features(), params, &mut progress)?;
        Ok(Self {
            trees,
            importances: Some(importances),
        })
    }

    /// Builds a model from raw flat arrays (one value per leaf), validated as [`load`](Self::load) does.
    pub fn from_parts(
        n_features: usize,
        nodes: Vec<Node>,
        offsets: Vec<u32>,
        leaf_values: Vec<f32>,
    ) -> Result<Self> {
        let parts = Parts {
            kind: Kind::Regressor,
            trees: FlatTrees {
                n_features,
                width: 1,
                nodes,
                offsets,
                leaf_values,
                walk: None,
            },
            labels: Vec::new(),
            importances: None,
        };
        format::validate_parts(&parts)?;
        Ok(Self {
            trees: parts.trees.finish(),
            importances: None,
        })
    }

    /// Number of features a row must have.
    pub fn n_features(&self) -> usize {
        self.trees.n_features
    }
    /// Number of trees.
    pub fn n_trees(&self) -> usize {
        self.trees.n_trees()
    }
    /// Total number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.trees.nodes.len()
    }
    /// Normalised mean decrease in impurity per feature, when known.
    pub fn feature_importances(&self) -> Option<&[f64]> {
        self.importances.as_deref()
    }

    /// Predicts row `x` (never panics; a short row reads missing features as NaN, which go right).
    pub fn predict(&self, x: &[f32]) -> f32 {
        let mut acc = [0f32; 1];
        self.trees.accumulate_row(x, &mut acc);
        acc[0] / self.n_trees() as f32
    }

    /// Like [`predict`](Self::predict), but checks that `x` has `n_features` finite values.
    pub fn try_predict(&self, x: &[f32]) -> Result<f32> {
        crate::classifier::check_row(x, self.trees.n_features)?;
        Ok(self.predict(x))
    }

    /// Predicts every row of `x` (row-major) into `out`.
    pub fn predict_batch(&self, x: &[f32], n_features: usize, out: &mut [f32]) -> Result<()> {
        if n_features != self.trees.n_features || Some(x.len()) != out.len().checked_mul(n_features)
        {
            return Err(ForestError::Shape(format!(
                "x has {} values for {} outputs with {n_features} features; the model expects {} features",
                x.len(),
                out.len(),
                self.trees.n_features
            )));
        }
        let scale = self.n_trees() as f32;
        let mut scratch = BlockScratch::default();
        for (xb, ob) in x
            .chunks(BLOCK_ROWS * n_features)
            .zip(out.chunks_mut(BLOCK_ROWS))
        {
            ob.fill(0.0);
            self.trees.accumulate_block(xb, ob, &mut scratch);
            for v in ob.iter_mut() {
                *v /= scale;
            }
        }
        Ok(())
    }

    /// Serialises the model.
    pub fn to_bytes(&self) -> Vec<u8> {
        format::encode(&self.parts())
    }
    /// Decodes and validates a serialised regressor.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        let p = format::decode(bytes, Kind::Regressor)?;
        Ok(Self {
            trees: p.trees,
            importances: p.importances,
        })
    }
    /// Writes the model file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        format::save(path.as_ref(), &self.parts())
    }
    /// Reads and validates a model file; errors name the file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let p = format::load(path.as_ref(), Kind::Regressor)?;
        Ok(Self {
            trees: p.trees,
            importances: p.importances,
        })
    }
    fn parts(&self) -> Parts {
        Parts {
            kind: Kind::Regressor,
            trees: self.trees.clone(),
            labels: Vec::new(),
            importances: self.importances.clone(),
        }
    }
}
