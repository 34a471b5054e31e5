//! Classification metrics: confusion matrix, accuracy, weighted precision and recall (as
//! scikit-learn's `precision_score(average="weighted")`), and regression error.

use serde::Serialize;

use crate::TactileError;

/// Counts of (true class, predicted class) pairs; rows are true classes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ConfusionMatrix {
    n_classes: usize,
    counts: Vec<u64>,
}

impl ConfusionMatrix {
    /// An empty matrix over `n_classes` classes.
    pub fn new(n_classes: usize) -> Self {
        ConfusionMatrix {
            n_classes,
            counts: vec![0; n_classes * n_classes],
        }
    }

    /// Builds the matrix from paired labels; errors on a label ≥ `n_classes` or unequal lengths.
    pub fn from_labels(
        n_classes: usize,
        truth: &[u32],
        predicted: &[u32],
    ) -> Result<Self, TactileError> {
        if truth.len() != predicted.len() {
            return Err(TactileError::LengthMismatch {
                truth: truth.len(),
                predicted: predicted.len(),
            });
        }
        let mut m = Self::new(n_classes);
        for (&t, &p) in truth.iter().zip(predicted) {
            m.add(t, p)?;
        }
        Ok(m)
    }

    /// Adds one pair.
    pub fn add(&mut self, truth: u32, predicted: u32) -> Result<(), TactileError> {
        let (t, p) = (truth as usize, predicted as usize);
        if t >= self.n_classes || p >= self.n_classes {
            return Err(TactileError::ClassOutOfRange {
                truth,
                predicted,
                n_classes: self.n_classes,
            });
        }
        self.counts[t * self.n_classes + p] += 1;
        Ok(())
    }

    /// Adds every count of `other` (same number of classes).
    pub fn merge(&mut self, other: &ConfusionMatrix) -> Result<(), TactileError> {
        if other.n_classes != self.n_classes {
            return Err(TactileError::ConfusionSize {
                expected: self.n_classes,
                found: other.n_classes,
            });
        }
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
        Ok(())
    }

    /// Number of classes.
    pub fn n_classes(&self) -> usize {
        self.n_classes
    }

    /// Count of samples of class `truth` predicted as `predicted`.
    pub fn get(&self, truth: usize, predicted: usize) -> u64 {
        self.counts
            .get(truth * self.n_classes + predicted)
            .copied()
            .unwrap_or(0)
    }

    /// Rows of the matrix (true classes), for printing and plotting.
    pub fn rows(&self) -> Vec<Vec<u64>> {
        self.counts
            .chunks(self.n_classes.max(1))
            .map(<[u64]>::to_vec)
            .collect()
    }

    /// Total number of samples.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Fraction predicted correctly (0 when empty).
    pub fn accuracy(&self) -> f64 {
        let correct: u64 = (0..self.n_classes).map(|c| self.get(c, c)).sum();
        ratio(correct, self.total())
    }

    fn support(&self, class: usize) -> u64 {
        (0..self.n_classes).map(|p| self.get(class, p)).sum()
    }

    fn predicted(&self, class: usize) -> u64 {
        (0..self.n_classes).map(|t| self.get(t, class)).sum()
    }

    /// Precision of one class (0 when it was never predicted, as scikit-learn's `zero_division=0`).
    pub fn precision(&self, class: usize) -> f64 {
        ratio(self.get(class, class), self.predicted(class))
    }

    /// Recall of one class (0 when it has no sample).
    pub fn recall(&self, class: usize) -> f64 {
        ratio(self.get(class, class), self.support(class))
    }

    /// Support-weighted mean of the per-class precisions.
    pub fn weighted_precision(&self) -> f64 {
        self.weighted(Self::precision)
    }

    /// Support-weighted mean of the per-class recalls (equals the accuracy).
    pub fn weighted_recall(&self) -> f64 {
        self.weighted(Self::recall)
    }

    fn weighted(&self, per_class: fn(&Self, usize) -> f64) -> f64 {
        let total = self.total();
        if total == 0 {
            return 0.0;
        }
        (0..self.n_classes)
            .map(|c| per_class(self, c) * self.support(c) as f64 / total as f64)
            .sum()
    }
}

fn ratio(a: u64, b: u64) -> f64 {
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

/// Mean absolute error between two equally long slices (NaN when empty).
pub fn mean_absolute_error(truth: &[f64], predicted: &[f64]) -> f64 {
    let n = truth.len().min(predicted.len());
    if n == 0 {
        return f64::NAN;
    }
    truth
        .iter()
        .zip(predicted)
        .map(|(t, p)| (t - p).abs())
        .sum::<f64>()
        / n as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_match_a_hand_computed_example() {
        // truth:     0 0 0 1 1 2
        // predicted: 0 0 1 1 2 2
        let m = ConfusionMatrix::from_labels(3, &[0, 0, 0, 1, 1, 2], &[0, 0, 1, 1, 2, 2]).unwrap();
        assert_eq!(m.rows(), vec![vec![2, 1, 0], vec![0, 1, 1], vec![0, 0, 1]]);
        assert!((m.accuracy() - 4.0 / 6.0).abs() < 1e-12);
        // Precision: class 0 2/2, class 1 1/2, class 2 1/2; supports 3, 2, 1.
        let expected = (1.0 * 3.0 + 0.5 * 2.0 + 0.5 * 1.0) / 6.0;
        assert!((m.weighted_precision() - expected).abs() < 1e-12);
        assert!((m.weighted_recall() - m.accuracy()).abs() < 1e-12);
    }

    #[test]
    fn never_predicted_class_has_zero_precision_and_bad_labels_are_errors() {
        let m = ConfusionMatrix::from_labels(2, &[0, 1], &[0, 0]).unwrap();
        assert_eq!(m.precision(1), 0.0);
        assert!(ConfusionMatrix::from_labels(2, &[0, 2], &[0, 0]).is_err());
        assert!(ConfusionMatrix::from_labels(2, &[0], &[0, 0]).is_err());
        assert_eq!(ConfusionMatrix::new(3).accuracy(), 0.0);
    }

    #[test]
    fn mae() {
        assert!((mean_absolute_error(&[0.0, 2.0, 10.0], &[1.0, 2.0, 8.0]) - 1.0).abs() < 1e-12);
        assert!(mean_absolute_error(&[], &[]).is_nan());
    }
}
