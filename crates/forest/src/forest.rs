//! The random-forest classifier: training and the flat, allocation-free inference model.

use std::path::Path;

use rayon::prelude::*;

use crate::classifier::{argmax, Classifier};
use crate::data::Dataset;
use crate::error::{ForestError, Result};
use crate::flat::{BlockScratch, FlatTrees, Node, BLOCK_ROWS};
use crate::format::{self, Kind, Parts};
use crate::params::ForestParams;
use crate::train::{train, Gini};

/// A trained random-forest classifier in the flat layout (see [`crate::flat`]).
///
/// Prediction = soft voting: the mean over trees of the leaf class probabilities (as scikit-learn), argmax
/// with the lowest class index on ties. Probabilities are summed in `f32` in tree order, so single-row and
/// batch predictions are bit-identical.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomForest {
    pub(crate) trees: FlatTrees,
    labels: Vec<f64>,
    importances: Option<Vec<f64>>,
}

impl RandomForest {
    /// Trains a forest on `data` (see [`ForestParams`] and the crate docs for the algorithm). Class labels
    /// default to `0.0, 1.0, …`; set them with [`with_class_labels`](Self::with_class_labels).
    pub fn fit(data: &Dataset, params: &ForestParams) -> Result<Self> {
        Self::fit_with_progress(data, params, |_, _| {})
    }

    /// [`fit`](Self::fit), reporting progress: `progress(done, total)` after each tree, one call at a time
    /// (from the training threads), `done` going 1, 2, … `total` = `params.n_trees` in order. Nothing is
    /// reported when `params.quiet` is set. The model is the same as [`fit`](Self::fit)'s.
    pub fn fit_with_progress(
        data: &Dataset,
        params: &ForestParams,
        mut progress: impl FnMut(usize, usize) + Send,
    ) -> Result<Self> {
        let task = Gini {
            y: data.y(),
            n_classes: data.n_classes(),
        };
        let (trees, importances) =
            train(&task, data.x(), data.n_features(), params, &mut progress)?;
        let labels = (0..data.n_classes()).map(|c| c as f64).collect();
        Ok(Self {
            trees,
            labels,
            importances: Some(importances),
        })
    }

    /// Builds a model from raw flat arrays (e.g. converted from another library), validating everything as
    /// [`load`](Self::load) does. `offsets` has `n_trees + 1` entries; `leaf_values` holds
    /// `labels.len()` probabilities per leaf.
    pub fn from_parts(
        n_features: usize,
        labels: Vec<f64>,
        nodes: Vec<Node>,
        offsets: Vec<u32>,
        leaf_values: Vec<f32>,
        importances: Option<Vec<f64>>,
    ) -> Result<Self> {
        let parts = Parts {
            kind: Kind::Classifier,
            trees: FlatTrees {
                n_features,
                width: labels.len(),
                nodes,
                offsets,
                leaf_values,
                walk: None,
            },
            labels,
            importances,
        };
        format::validate_parts(&parts)?;
        Ok(Self {
            trees: parts.trees.finish(),
            labels: parts.labels,
            importances: parts.importances,
        })
    }

    /// Replaces the class labels (one finite `f64` per class, e.g. crack widths in mm).
    pub fn with_class_labels(mut self, labels: Vec<f64>) -> Result<Self> {
        if labels.len() != self.labels.len() || labels.iter().any(|v| !v.is_finite()) {
            return Err(ForestError::InvalidParams(format!(
                "need {} finite class labels, got {:?}",
                self.labels.len(),
                labels
            )));
        }
        self.labels = labels;
        Ok(self)
    }

    /// Class labels, indexed by class.
    pub fn class_labels(&self) -> &[f64] {
        &self.labels
    }
    /// Label of the predicted class of row `x`.
    pub fn predict_label(&self, x: &[f32]) -> f64 {
        self.labels
            .get(self.predict(x) as usize)
            .copied()
            .unwrap_or(f64::NAN)
    }
    /// Normalised mean decrease in impurity per feature (sums to 1), when known.
    pub fn feature_importances(&self) -> Option<&[f64]> {
        self.importances.as_deref()
    }
    /// Number of trees.
    pub fn n_trees(&self) -> usize {
        self.trees.n_trees()
    }
    /// Total number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.trees.nodes.len()
    }
    /// Depth of the deepest leaf.
    pub fn max_depth(&self) -> usize {
        self.trees.max_depth()
    }
    /// All nodes (depth-first pre-order per tree).
    pub fn nodes(&self) -> &[Node] {
        &self.trees.nodes
    }
    /// `n_trees + 1` offsets of the trees in [`nodes`](Self::nodes).
    pub fn tree_offsets(&self) -> &[u32] {
        &self.trees.offsets
    }
    /// Leaf probability table (`n_classes` values per leaf id).
    pub fn leaf_values(&self) -> &[f32] {
        &self.trees.leaf_values
    }

    /// Predicts the class of every row of `x` (row-major, `n_features` per row) into `out` (one per row).
    ///
    /// Rows are processed in blocks of 8192; within a block, each tree moves all rows down one level at a
    /// time (see [`crate::flat`]), which keeps the tree in cache and overlaps the memory latency of the
    /// independent traversals. Allocates per call (block buffers), never per row. Results equal
    /// [`predict`](Classifier::predict) row by row.
    pub fn predict_batch(&self, x: &[f32], n_features: usize, out: &mut [u32]) -> Result<()> {
        self.check_batch(x, n_features, out.len())?;
        let k = self.labels.len();
        let mut acc = vec![0f32; BLOCK_ROWS.min(out.len()) * k];
        let mut scratch = BlockScratch::default();
        for (xb, ob) in x
            .chunks(BLOCK_ROWS * n_features)
            .zip(out.chunks_mut(BLOCK_ROWS))
        {
            let acc = &mut acc[..ob.len() * k];
            acc.fill(0.0);
            self.trees.accumulate_block(xb, acc, &mut scratch);
            for (o, p) in ob.iter_mut().zip(acc.chunks_exact(k)) {
                *o = argmax(p);
            }
        }
        Ok(())
    }

    /// Class probabilities of every row of `x` into `out` (`n_classes` per row, row-major).
    pub fn predict_proba_batch(&self, x: &[f32], n_features: usize, out: &mut [f32]) -> Result<()> {
        let k = self.labels.len();
        if !out.len().is_multiple_of(k) {
            return Err(ForestError::Shape(format!(
                "output length {} is not a multiple of {k} classes",
                out.len()
            )));
        }
        self.check_batch(x, n_features, out.len() / k)?;
        let scale = 1.0 / self.n_trees() as f32;
        let mut scratch = BlockScratch::default();
        for (xb, ob) in x
            .chunks(BLOCK_ROWS * n_features)
            .zip(out.chunks_mut(BLOCK_ROWS * k))
        {
            ob.fill(0.0);
            self.trees.accumulate_block(xb, ob, &mut scratch);
            for v in ob.iter_mut() {
                *v *= scale;
            }
        }
        Ok(())
    }

    /// [`predict_batch`](Self::predict_batch) split over rayon's threads.
    pub fn par_predict_batch(&self, x: &[f32], n_features: usize, out: &mut [u32]) -> Result<()> {
        self.check_batch(x, n_features, out.len())?;
        const CHUNK: usize = 4 * BLOCK_ROWS;
        x.par_chunks(CHUNK * n_features)
            .zip(out.par_chunks_mut(CHUNK))
            .try_for_each(|(xc, oc)| self.predict_batch(xc, n_features, oc))
    }

    fn check_batch(&self, x: &[f32], n_features: usize, rows: usize) -> Result<()> {
        if n_features != self.trees.n_features {
            return Err(ForestError::Shape(format!(
                "{n_features} features given, the model expects {}",
                self.trees.n_features
            )));
        }
        if Some(x.len()) != rows.checked_mul(n_features) {
            return Err(ForestError::Shape(format!(
                "x has {} values, expected {rows} rows × {n_features} features",
                x.len()
            )));
        }
        Ok(())
    }

    /// Serialises the model (see [`crate::format`]).
    pub fn to_bytes(&self) -> Vec<u8> {
        format::encode(&self.parts())
    }
    /// Decodes and validates a serialised model.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self> {
        Ok(Self::from_decoded(format::decode(bytes, Kind::Classifier)?))
    }
    /// Writes the model file.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        format::save(path.as_ref(), &self.parts())
    }
    /// Reads and validates a model file; errors name the file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        Ok(Self::from_decoded(format::load(
            path.as_ref(),
            Kind::Classifier,
        )?))
    }

    fn parts(&self) -> Parts {
        Parts {
            kind: Kind::Classifier,
            trees: self.trees.clone(),
            labels: self.labels.clone(),
            importances: self.importances.clone(),
        }
    }
    fn from_decoded(p: Parts) -> Self {
        Self {
            trees: p.trees,
            labels: p.labels,
            importances: p.importances,
        }
    }
}

impl Classifier for RandomForest {
    fn n_classes(&self) -> usize {
        self.labels.len()
    }
    fn n_features(&self) -> usize {
        self.trees.n_features
    }
    fn predict_proba_into(&self, x: &[f32], out: &mut [f32]) {
        let k = self.labels.len();
        if out.len() >= k {
            let out = &mut out[..k];
            out.fill(0.0);
            self.trees.accumulate_row(x, out);
            let scale = 1.0 / self.n_trees() as f32;
            for v in out.iter_mut() {
                *v *= scale;
            }
        } else {
            let mut buf = vec![0f32; k];
            self.predict_proba_into(x, &mut buf);
            out.copy_from_slice(&buf[..out.len()]);
        }
    }
    fn predict(&self, x: &[f32]) -> u32 {
        let k = self.labels.len();
        if k <= 16 {
            let mut buf = [0f32; 16];
            self.trees.accumulate_row(x, &mut buf[..k]);
            argmax(&buf[..k])
        } else {
            let mut buf = vec![0f32; k];
            self.trees.accumulate_row(x, &mut buf);
            argmax(&buf)
        }
    }
}
