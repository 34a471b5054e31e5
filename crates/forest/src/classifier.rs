//! The [`Classifier`] trait shared by the forest, KNN and QDA.

use crate::error::{ForestError, Result};

/// Index of the largest value; the lowest index wins ties, NaNs are ignored, and an empty or all-NaN slice
/// gives 0.
pub fn argmax(p: &[f32]) -> u32 {
    let mut best = 0usize;
    let mut best_v = f32::NEG_INFINITY;
    let mut seen = false;
    for (i, &v) in p.iter().enumerate() {
        if v.is_nan() {
            continue;
        }
        if !seen || v > best_v {
            best = i;
            best_v = v;
            seen = true;
        }
    }
    best as u32
}

/// Largest class count for which the default [`Classifier::predict`] uses a stack buffer.
const STACK_CLASSES: usize = 64;

/// A trained classifier over `n_features` `f32` features and `n_classes` classes.
///
/// `predict_proba_into` and `predict` never allocate (for up to 64 classes) and never panic: a row shorter
/// than [`n_features`](Classifier::n_features) reads the missing features as NaN, extra values are ignored,
/// and only `min(out.len(), n_classes)` probabilities are written. Use the `try_` variants to get an error
/// on such shape mismatches instead.
pub trait Classifier {
    /// Number of classes (length of a probability vector).
    fn n_classes(&self) -> usize;

    /// Number of features a row must have.
    fn n_features(&self) -> usize;

    /// Writes the class probabilities of row `x` into `out[..n_classes]`.
    fn predict_proba_into(&self, x: &[f32], out: &mut [f32]);

    /// Most probable class of row `x` (argmax of the probabilities, the lowest index on ties).
    fn predict(&self, x: &[f32]) -> u32 {
        let k = self.n_classes();
        if k <= STACK_CLASSES {
            let mut buf = [0f32; STACK_CLASSES];
            self.predict_proba_into(x, &mut buf[..k]);
            argmax(&buf[..k])
        } else {
            let mut buf = vec![0f32; k];
            self.predict_proba_into(x, &mut buf);
            argmax(&buf)
        }
    }

    /// Class probabilities of row `x` as a new vector.
    fn predict_proba(&self, x: &[f32]) -> Vec<f32> {
        let mut out = vec![0f32; self.n_classes()];
        self.predict_proba_into(x, &mut out);
        out
    }

    /// Like [`predict_proba_into`](Classifier::predict_proba_into), but checks the lengths of `x` and `out`
    /// and that `x` is finite.
    fn try_predict_proba_into(&self, x: &[f32], out: &mut [f32]) -> Result<()> {
        check_row(x, self.n_features())?;
        if out.len() != self.n_classes() {
            return Err(ForestError::Shape(format!(
                "output has {} slots, the model has {} classes",
                out.len(),
                self.n_classes()
            )));
        }
        self.predict_proba_into(x, out);
        Ok(())
    }

    /// Like [`predict`](Classifier::predict), but checks the length of `x` and that it is finite.
    fn try_predict(&self, x: &[f32]) -> Result<u32> {
        check_row(x, self.n_features())?;
        Ok(self.predict(x))
    }
}

/// Checks one input row: `n_features` finite values.
pub(crate) fn check_row(x: &[f32], n_features: usize) -> Result<()> {
    if x.len() != n_features {
        return Err(ForestError::Shape(format!(
            "row has {} features, the model expects {n_features}",
            x.len()
        )));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(ForestError::NonFinite {
            row: 0,
            column: i,
            value: x[i],
        });
    }
    Ok(())
}

/// Accuracy of `model` on `data` (fraction of rows predicted correctly).
pub fn accuracy<C: Classifier + ?Sized>(model: &C, data: &crate::Dataset) -> f64 {
    let n = data.n_rows();
    let correct = (0..n)
        .filter(|&i| {
            data.row(i)
                .is_some_and(|row| model.predict(row) == data.y()[i])
        })
        .count();
    correct as f64 / n.max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argmax_ties_and_nan() {
        assert_eq!(argmax(&[0.2, 0.4, 0.4]), 1);
        assert_eq!(argmax(&[0.5, 0.5]), 0);
        assert_eq!(argmax(&[f32::NAN, 0.1, 0.3]), 2);
        assert_eq!(argmax(&[f32::NAN, f32::NAN]), 0);
        assert_eq!(argmax(&[]), 0);
        assert_eq!(argmax(&[f32::NEG_INFINITY, f32::NEG_INFINITY]), 0);
    }
}
