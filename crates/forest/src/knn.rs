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
    /// Training row indices sorted by their first (standardised) feature, and that feature's
    /// values in the same order: the search sweeps outwards from the query along feature 0 and
    /// stops once that coordinate alone is farther than the current k-th neighbour.
    by_first: Vec<u32>,
    first: Vec<f32>,
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
        let x: Vec<f32> = x;
        let mut by_first: Vec<u32> = (0..n as u32).collect();
        by_first.sort_by(|&a, &b| {
            x[a as usize * nf]
                .total_cmp(&x[b as usize * nf])
                .then(a.cmp(&b))
        });
        let first = by_first.iter().map(|&r| x[r as usize * nf]).collect();
        Ok(Self {
            k: params.k,
            n_features: nf,
            n_classes: data.n_classes(),
            x,
            y: data.y().to_vec(),
            mean,
            inv_std,
            by_first,
            first,
        })
    }

    /// Number of neighbours.
    pub fn k(&self) -> usize {
        self.k
    }

    fn vote(&self, q: &[f32], out: &mut [f32]) {
        let nf = self.n_features;
        let k = self.k;
        if q.iter().any(|v| v.is_nan()) {
            for v in out.iter_mut() {
                *v = f32::NAN;
            }
            return;
        }
        // Sorted ascending by (distance, row); `len` valid entries. Ties in distance go to the
        // earlier training row, whatever order the rows are visited in.
        let mut best = [(f32::INFINITY, u32::MAX); MAX_K];
        let mut len = 0usize;
        let consider = |r: u32, best: &mut [(f32, u32); MAX_K], len: &mut usize| {
            let row = &self.x[r as usize * nf..(r as usize + 1) * nf];
            let mut d = 0f32;
            for (a, b) in row.iter().zip(q) {
                let t = a - b;
                d += t * t;
            }
            if *len == k && (d, r) >= best[k - 1] {
                return;
            }
            let mut i = (*len).min(k - 1);
            while i > 0 && best[i - 1] > (d, r) {
                best[i] = best[i - 1];
                i -= 1;
            }
            best[i] = (d, r);
            *len = (*len + 1).min(k);
        };
        // Sweep outwards from the query along feature 0. The squared distance is a sum of
        // non-negative terms in feature order, so it is never below its first term (rounding is
        // monotone): once a side's first term exceeds the k-th distance, that side is done.
        let q0 = q.first().copied().unwrap_or(0.0);
        let gap = |v: f32| {
            let t = v - q0;
            t * t
        };
        let mut right = self.first.partition_point(|&v| v < q0);
        let mut left = right;
        loop {
            let kth = if len == k {
                best[k - 1].0
            } else {
                f32::INFINITY
            };
            let l = (left > 0)
                .then(|| gap(self.first[left - 1]))
                .filter(|&g| g <= kth);
            let r = (right < self.first.len())
                .then(|| gap(self.first[right]))
                .filter(|&g| g <= kth);
            match (l, r) {
                (None, None) => break,
                (Some(gl), Some(gr)) if gl < gr => {
                    left -= 1;
                    consider(self.by_first[left], &mut best, &mut len);
                }
                (Some(_), None) => {
                    left -= 1;
                    consider(self.by_first[left], &mut best, &mut len);
                }
                _ => {
                    consider(self.by_first[right], &mut best, &mut len);
                    right += 1;
                }
            }
        }
        for v in out.iter_mut() {
            *v = 0.0;
        }
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

    /// The plain exhaustive search the sweep must reproduce exactly.
    fn brute_force(m: &Knn, q: &[f32]) -> Vec<u32> {
        let nf = m.n_features;
        let mut d: Vec<(f32, u32)> =
            m.x.chunks_exact(nf)
                .enumerate()
                .map(|(r, row)| {
                    let mut s = 0f32;
                    for (a, b) in row.iter().zip(q) {
                        s += (a - b) * (a - b);
                    }
                    (s, r as u32)
                })
                .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        d[..m.k].iter().map(|&(_, r)| m.y[r as usize]).collect()
    }

    #[test]
    fn sweep_matches_exhaustive_search_with_many_ties() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        // Integer-valued features: many exact distance ties.
        let n = 600;
        let x: Vec<f32> = (0..n * 3).map(|_| rng.random_range(0..12) as f32).collect();
        let y: Vec<u32> = (0..n).map(|_| rng.random_range(0..4)).collect();
        let d = Dataset::new(x, 3, y).unwrap();
        for standardize in [false, true] {
            let m = Knn::fit(&d, KnnParams { k: 5, standardize }).unwrap();
            for _ in 0..400 {
                let q: Vec<f32> = (0..3)
                    .map(|_| rng.random_range(-2.0..14.0f32).round())
                    .collect();
                let mut sq = q.clone();
                for (f, v) in sq.iter_mut().enumerate() {
                    *v = (*v - m.mean[f]) * m.inv_std[f];
                }
                let mut expected = vec![0f32; 4];
                for c in brute_force(&m, &sq) {
                    expected[c as usize] += 1.0 / 5.0;
                }
                assert_eq!(m.predict_proba(&q), expected, "query {q:?}");
            }
        }
    }

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
