//! Pixel-level precision, recall and F1 of a crack map against a crack mask, the way the crack
//! segmentation literature reports them (CrackForest, DeepCrack): with a distance tolerance, over
//! a sweep of thresholds, at the best single threshold for the whole dataset (ODS) and the best
//! threshold of each image (OIS).
//!
//! With a tolerance of `τ` pixels, a predicted crack pixel is correct when a ground-truth crack
//! pixel lies within `τ` (Euclidean) and a ground-truth pixel is found when a predicted pixel lies
//! within `τ`. Both counts come from one pass per image: the mask dilated by a disk of radius
//! `τ` (precision) and the map max-filtered over the same disk (recall), binned over the
//! thresholds.

use serde::Serialize;

use crate::VisionError;

/// Thresholds swept: `(k + 1) / (THRESHOLDS + 1)` for `k = 0 … THRESHOLDS − 1` (0.01, 0.02, …, 0.99).
pub const THRESHOLDS: usize = 99;
/// Index of the threshold 0.5 in the sweep.
const HALF: usize = 49;

/// Counts of one image or a whole dataset, per threshold.
#[derive(Debug, Clone, PartialEq)]
struct Counts {
    /// Predicted pixels at each threshold.
    predicted: Vec<u64>,
    /// Predicted pixels within the tolerance of a ground-truth pixel.
    predicted_correct: Vec<u64>,
    /// Ground-truth pixels within the tolerance of a predicted pixel.
    found: Vec<u64>,
    /// Ground-truth pixels.
    truth: u64,
}

impl Counts {
    fn new() -> Self {
        Counts {
            predicted: vec![0; THRESHOLDS],
            predicted_correct: vec![0; THRESHOLDS],
            found: vec![0; THRESHOLDS],
            truth: 0,
        }
    }

    fn add(&mut self, other: &Counts) {
        for k in 0..THRESHOLDS {
            self.predicted[k] += other.predicted[k];
            self.predicted_correct[k] += other.predicted_correct[k];
            self.found[k] += other.found[k];
        }
        self.truth += other.truth;
    }

    /// Precision, recall and F1 at threshold index `k` (precision 1 with nothing predicted,
    /// recall 1 with nothing to find).
    fn at(&self, k: usize) -> PixelScore {
        let precision = if self.predicted[k] == 0 {
            1.0
        } else {
            self.predicted_correct[k] as f64 / self.predicted[k] as f64
        };
        let recall = if self.truth == 0 {
            1.0
        } else {
            self.found[k] as f64 / self.truth as f64
        };
        let f1 = if precision + recall > 0.0 {
            2.0 * precision * recall / (precision + recall)
        } else {
            0.0
        };
        PixelScore {
            threshold: threshold(k),
            precision,
            recall,
            f1,
        }
    }

    fn best(&self) -> PixelScore {
        (0..THRESHOLDS)
            .map(|k| self.at(k))
            .fold(None::<PixelScore>, |best, s| match best {
                Some(b) if b.f1 >= s.f1 => Some(b),
                _ => Some(s),
            })
            .unwrap_or(PixelScore {
                threshold: 0.5,
                precision: 1.0,
                recall: 1.0,
                f1: 1.0,
            })
    }
}

/// Threshold number `k` of the sweep.
pub fn threshold(k: usize) -> f64 {
    (k as f64 + 1.0) / (THRESHOLDS + 1) as f64
}

/// Precision, recall and F1 at one threshold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PixelScore {
    /// The threshold on the crack probability.
    pub threshold: f64,
    /// Fraction of predicted crack pixels near a true one.
    pub precision: f64,
    /// Fraction of true crack pixels near a predicted one.
    pub recall: f64,
    /// Their harmonic mean.
    pub f1: f64,
}

/// The pixel-level metrics of a dataset at one tolerance.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PixelMetrics {
    /// Tolerance, pixels.
    pub tolerance_px: f64,
    /// Images with a mask.
    pub images: usize,
    /// Best F1 at one threshold for the whole dataset.
    pub ods: PixelScore,
    /// Mean over images of each image's best F1.
    pub ois_f1: f64,
    /// At the detector's own map threshold (0.5).
    pub at_half: PixelScore,
}

/// Accumulates images into [`PixelMetrics`].
#[derive(Debug, Clone)]
pub struct PixelEvaluator {
    tolerance: f64,
    offsets: Vec<(isize, isize)>,
    total: Counts,
    per_image_best: Vec<f64>,
}

impl PixelEvaluator {
    /// An evaluator with a tolerance of `tolerance_px` pixels (≥ 0, finite).
    pub fn new(tolerance_px: f64) -> Result<Self, VisionError> {
        if !(tolerance_px.is_finite() && (0.0..=50.0).contains(&tolerance_px)) {
            return Err(VisionError::setting(
                "pixel tolerance_px",
                tolerance_px,
                "in [0, 50] px",
            ));
        }
        let r = tolerance_px.floor() as isize;
        let offsets = (-r..=r)
            .flat_map(|dy| (-r..=r).map(move |dx| (dy, dx)))
            .filter(|&(dy, dx)| ((dx * dx + dy * dy) as f64) <= tolerance_px * tolerance_px)
            .collect();
        Ok(Self {
            tolerance: tolerance_px,
            offsets,
            total: Counts::new(),
            per_image_best: Vec::new(),
        })
    }

    /// Adds one image: `prob` (crack probabilities) and `truth` (crack mask), both `width ×
    /// height`, row-major. Errors when the sizes disagree or a probability is not in [0, 1].
    pub fn add(
        &mut self,
        prob: &[f32],
        truth: &[bool],
        width: usize,
        height: usize,
    ) -> Result<(), VisionError> {
        crate::error::check_sizes(prob.len(), truth.len(), width, height)?;
        if let Some(v) = prob
            .iter()
            .find(|v| !(v.is_finite() && (0.0..=1.0).contains(*v)))
        {
            return Err(VisionError::NotProbability { value: *v });
        }
        let mut near_truth = vec![false; truth.len()];
        let mut max_near = vec![0f32; prob.len()];
        for y in 0..height {
            for x in 0..width {
                let i = y * width + x;
                let mut m = 0f32;
                for &(dy, dx) in &self.offsets {
                    let (yy, xx) = (y as isize + dy, x as isize + dx);
                    if yy < 0 || xx < 0 || yy as usize >= height || xx as usize >= width {
                        continue;
                    }
                    let j = yy as usize * width + xx as usize;
                    m = m.max(prob[j]);
                    if truth[j] {
                        near_truth[i] = true;
                    }
                }
                max_near[i] = m;
            }
        }
        let mut c = Counts::new();
        // Pixel counted at thresholds 0..=bin(p): the thresholds t_k ≤ p.
        let bin = |p: f32| -> Option<usize> {
            let k = (f64::from(p) * (THRESHOLDS + 1) as f64 - 1.0).floor();
            (k >= 0.0).then(|| (k as usize).min(THRESHOLDS - 1))
        };
        let mut pred_hist = vec![0u64; THRESHOLDS];
        let mut correct_hist = vec![0u64; THRESHOLDS];
        let mut found_hist = vec![0u64; THRESHOLDS];
        for i in 0..prob.len() {
            if let Some(k) = bin(prob[i]) {
                pred_hist[k] += 1;
                if near_truth[i] {
                    correct_hist[k] += 1;
                }
            }
            if truth[i] {
                c.truth += 1;
                if let Some(k) = bin(max_near[i]) {
                    found_hist[k] += 1;
                }
            }
        }
        // Cumulative from the top: a pixel in bin k counts for every threshold ≤ t_k.
        let (mut p, mut q, mut f) = (0, 0, 0);
        for k in (0..THRESHOLDS).rev() {
            p += pred_hist[k];
            q += correct_hist[k];
            f += found_hist[k];
            c.predicted[k] = p;
            c.predicted_correct[k] = q;
            c.found[k] = f;
        }
        self.per_image_best.push(c.best().f1);
        self.total.add(&c);
        Ok(())
    }

    /// The metrics of the images added so far (`None` before the first).
    pub fn finish(&self) -> Option<PixelMetrics> {
        if self.per_image_best.is_empty() {
            return None;
        }
        Some(PixelMetrics {
            tolerance_px: self.tolerance,
            images: self.per_image_best.len(),
            ods: self.total.best(),
            ois_f1: self.per_image_best.iter().sum::<f64>() / self.per_image_best.len() as f64,
            at_half: self.total.at(HALF),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_perfect_map_scores_one_and_an_empty_one_finds_nothing() {
        let (w, h) = (20, 10);
        let truth: Vec<bool> = (0..w * h).map(|i| i % w == 7).collect();
        let prob: Vec<f32> = truth.iter().map(|&t| if t { 0.9 } else { 0.05 }).collect();
        let mut e = PixelEvaluator::new(0.0).unwrap();
        e.add(&prob, &truth, w, h).unwrap();
        let m = e.finish().unwrap();
        assert_eq!(m.ods.f1, 1.0);
        assert_eq!(m.at_half.precision, 1.0);
        let mut e = PixelEvaluator::new(2.0).unwrap();
        e.add(&vec![0.0; w * h], &truth, w, h).unwrap();
        assert_eq!(e.finish().unwrap().at_half.recall, 0.0);
    }

    #[test]
    fn the_tolerance_forgives_a_one_pixel_shift_and_not_a_five_pixel_one() {
        let (w, h) = (30, 10);
        let truth: Vec<bool> = (0..w * h).map(|i| i % w == 10).collect();
        let shifted = |d: usize| -> Vec<f32> {
            (0..w * h)
                .map(|i| if i % w == 10 + d { 1.0 } else { 0.0 })
                .collect()
        };
        for (d, tol, f1) in [(1, 0.0, 0.0), (1, 2.0, 1.0), (5, 2.0, 0.0)] {
            let mut e = PixelEvaluator::new(tol).unwrap();
            e.add(&shifted(d), &truth, w, h).unwrap();
            assert_eq!(e.finish().unwrap().at_half.f1, f1, "shift {d} tol {tol}");
        }
    }

    #[test]
    fn the_sweep_holds_one_half() {
        assert_eq!(threshold(HALF), 0.5);
        assert!(
            (threshold(0) - 0.01).abs() < 1e-12 && (threshold(THRESHOLDS - 1) - 0.99).abs() < 1e-12
        );
    }

    #[test]
    fn bad_inputs_are_errors() {
        assert!(PixelEvaluator::new(f64::NAN).is_err());
        assert!(PixelEvaluator::new(-1.0).is_err());
        let mut e = PixelEvaluator::new(1.0).unwrap();
        assert!(e.add(&[0.5; 3], &[false; 4], 2, 2).is_err());
        assert!(e
            .add(&[0.5, 0.5, f32::NAN, 0.5], &[false; 4], 2, 2)
            .is_err());
        assert!(e.finish().is_none());
    }

    proptest! {
        /// The binned counts equal a direct count at every threshold.
        #[test]
        fn binned_counts_match_a_direct_count(
            prob in proptest::collection::vec(0f32..=1.0, 48),
            truth in proptest::collection::vec(any::<bool>(), 48),
            k in 0usize..THRESHOLDS,
        ) {
            let (w, h) = (8, 6);
            let mut e = PixelEvaluator::new(1.0).unwrap();
            e.add(&prob, &truth, w, h).unwrap();
            let t = threshold(k);
            let near = |i: usize, f: &dyn Fn(usize) -> bool| {
                let (x, y) = ((i % w) as isize, (i / w) as isize);
                [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dx, dy)| {
                    let (xx, yy) = (x + dx, y + dy);
                    xx >= 0 && yy >= 0 && xx < w as isize && yy < h as isize
                        && f(yy as usize * w + xx as usize)
                })
            };
            let pred: Vec<usize> = (0..48).filter(|&i| f64::from(prob[i]) >= t).collect();
            let correct = pred.iter().filter(|&&i| near(i, &|j| truth[j])).count() as u64;
            let found = (0..48).filter(|&i| truth[i] && near(i, &|j| f64::from(prob[j]) >= t)).count() as u64;
            prop_assert_eq!(e.total.predicted[k], pred.len() as u64);
            prop_assert_eq!(e.total.predicted_correct[k], correct);
            prop_assert_eq!(e.total.found[k], found);
        }
    }
}
