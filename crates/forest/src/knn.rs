//! k-nearest-neighbours classifier (the paper's KNN, k = 5, Euclidean).

use crate::classifier::Classifier;
use crate::data::Dataset;
use crate::error::{ForestError, Result};

/// Largest supported `k` (the neighbour list lives on the stack).
pub const MAX_K: usize = 64;
/// Largest feature count for which the standardised query lives on the stack.
const STACK_FEATURES: usize = 64;

/// Parameters of [`Knn::fit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KnnParams {
    /// Number of neighbours (1..=64, at most the number of training rows).
    pub k: usize,
    /// Standardise every feature (zero mean, unit variance on the training set; a constant feature keeps
    /// scale 1) before measuring distances.
    pub standardize: bool,
}

impl Default for KnnParams {
    /// k = 5 (as the paper and scikit-learn), no standardisation (as scikit-learn's plain `KNeighborsClassifier`).
    fn default() -> Self {
        Self {
            k: 5,
            standardize: false,
        }
    }
}

/// A fitted KNN classifier: the (optionally standardised) training rows and their classes.
///
/// The probability of a class is the fraction of the `k` nearest training rows (squared Euclidean distance,
/// `f32`) that have it, as scikit-learn's uniform weights. Distance ties are broken by the training row
/// index (the earlier row is nearer); class ties of `predict` go to the lowest class index. The search is
/// exhaustive (O(n_rows · n_features) per query, ~0.1 ms for 75k × 3), allocation-free for up to 64
/// features. A NaN in the query gives NaN probabilities (use `try_predict` to reject it).
#[derive(Debug, Clone, PartialEq)]
pub struct Knn {
    k: usize,
    n_features: usize,
    n_classes: usize,
    x: Vec<f32>,
    y: Vec<u32>,
    mean: Vec<f32>,
    inv_std: Vec<f32>,
}

impl Knn {
    /// Stores the training data.
    pub fn fit(data: &Dataset, params: KnnParams) -> Result<Self> {
        if params.k == 0 || params.k > MAX_K {
            return Err(ForestError::InvalidParams(format!(
                "k = {} not in 1..={MAX_K}",
                params.k
            )));
        }
        if params.k > data.n_rows() {
            return Err(ForestError::InvalidParams(format!(
                "k = {} is more than the {} training rows",
                params.k,
                data.n_rows()
            )));
        }
        let nf = data.n_features();
        let n = data.n_rows();
        let (mut mean, mut inv_std) = (vec![0f32; nf], vec![1f32; nf]);
        if params.standardize {
            for f in 0..nf {
                let m = (0..n).map(|r| data.x()[r * nf + f] as f64).sum::<f64>() / n as f64;
                let var = (0..n)
                    .map(|r| (data.x()[r * nf + f] as f64 - m).powi(2))
                    .sum::<f64>()
                    / n as f64;
                mean[f] = m as f32;
                let sd = var.sqrt();
                inv_std[f] = if sd > 1e-12 * m.abs().max(1.0) {
                    (1.0 / sd) as f32
                } else {
                    1.0
                };
            }
        }
        let x = data
            .x()
            .chunks_exact(nf)
            .flat_map(|row| {
                row.iter()
                    .zip(mean.iter().zip(&inv_std))
                    .map(|(v, (m, s))| (v - m) * s)
            })
            .collect();
        Ok(Self {
            k: params.k,
            n_features: nf,
            n_classes: data.n_classes(),
            x,
            y: data.y().to_vec(),
            mean,
            inv_std,
        })
    }

    /// Number of neighbours.
    pub fn k(&self) -> usize {
        self.k
    }

    fn vote(&self, q: &[f32], out: &mut [f32]) {
        let nf = self.n_features;
        let k = self.k;
        // Sorted ascending by (distance, row); `len` valid entries.
        let mut best = [(f32::INFINITY, u32::MAX); MAX_K];
        let mut len = 0usize;
        for (r, row) in self.x.chunks_exact(nf).enumerate() {
            let mut d = 0f32;
            for (a, b) in row.iter().zip(q) {
                let t = a - b;
                d += t * t;
            }
            if len == k && d >= best[k - 1].0 {
                continue; // not nearer than the current k-th (ties: earlier rows win)
            }
            if d.is_nan() {
                out.iter_mut().for_each(|v| *v = f32::NAN);
                return;
            }
            let mut i = len.min(k - 1);
            while i > 0 && best[i - 1].0 > d {
                best[i] = best[i - 1];
                i -= 1;
            }
            best[i] = (d, r as u32);
            len = (len + 1).min(k);
        }
        out.iter_mut().for_each(|v| *v = 0.0);
        let w = 1.0 / len.max(1) as f32;
        for &(_, r) in &best[..len] {
            if let Some(slot) = self
                .y
                .get(r as usize)
                .and_then(|&c| out.get_mut(c as usize))
            {
                *slot += w;
            }
        }
    }
}

impl Classifier for Knn {
    fn n_classes(&self) -> usize {
        self.n_classes
    }
    fn n_features(&self) -> usize {
        self.n_features
    }
    fn predict_proba_into(&self, x: &[f32], out: &mut [f32]) {
        let nf = self.n_features;
        let k = self.n_classes.min(out.len());
        let out = &mut out[..k];
        let std_row = |buf: &mut [f32]| {
            for (f, b) in buf.iter_mut().enumerate() {
                *b = (x.get(f).copied().unwrap_or(f32::NAN) - self.mean[f]) * self.inv_std[f];
            }
        };
        if nf <= STACK_FEATURES {
            let mut buf = [0f32; STACK_FEATURES];
            std_row(&mut buf[..nf]);
            self.vote(&buf[..nf], out);
        } else {
            let mut buf = vec![0f32; nf];
            std_row(&mut buf);
            self.vote(&buf, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_neighbours_and_ties() {
        // 1-D: rows at 0, 1, 2, 3, 10 with classes 0, 1, 1, 0, 2.
        let d = Dataset::new(vec![0.0, 1.0, 2.0, 3.0, 10.0], 1, vec![0, 1, 1, 0, 2]).unwrap();
        let m = Knn::fit(
            &d,
            KnnParams {
                k: 1,
                standardize: false,
            },
        )
        .unwrap();
        assert_eq!(m.predict(&[9.0]), 2);
        assert_eq!(m.predict(&[0.4]), 0);
        // 0.5 is equidistant from rows 0 (class 0) and 1 (class 1): the earlier row wins.
        assert_eq!(m.predict(&[0.5]), 0);
        let m = Knn::fit(
            &d,
            KnnParams {
                k: 2,
                standardize: false,
            },
        )
        .unwrap();
        // Neighbours of 1.5: rows 1 and 2 (both class 1).
        assert_eq!(m.predict_proba(&[1.5]), vec![0.0, 1.0, 0.0]);
        // Neighbours of 0.5: rows 0 and 1: a class tie goes to the lowest class.
        assert_eq!(m.predict(&[0.5]), 0);
        let m = Knn::fit(
            &d,
            KnnParams {
                k: 5,
                standardize: true,
            },
        )
        .unwrap();
        let p = m.predict_proba(&[1.0]);
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        assert!(m.predict_proba(&[f32::NAN]).iter().all(|v| v.is_nan()));
        assert!(m.try_predict(&[f32::NAN]).is_err());
        assert!(m.try_predict(&[1.0, 2.0]).is_err());
        let _ = m.predict(&[]); // never panics
    }

    #[test]
    fn bad_k() {
        let d = Dataset::new(vec![0.0, 1.0], 1, vec![0, 1]).unwrap();
        assert!(Knn::fit(
            &d,
            KnnParams {
                k: 0,
                standardize: false
            }
        )
        .is_err());
        assert!(Knn::fit(
            &d,
            KnnParams {
                k: 3,
                standardize: false
            }
        )
        .is_err());
        assert!(Knn::fit(
            &d,
            KnnParams {
                k: 65,
                standardize: false
            }
        )
        .is_err());
    }
}
