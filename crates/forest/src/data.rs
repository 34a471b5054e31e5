//! Validated training data: row-major `f32` features with class indices or regression targets.

use crate::error::{ForestError, Result};

fn check_features(x: &[f32], n_features: usize, n_rows: usize) -> Result<()> {
    if n_features == 0 {
        return Err(ForestError::InvalidData(
            "n_features must be at least 1".into(),
        ));
    }
    if n_features > u32::MAX as usize / 2 {
        return Err(ForestError::InvalidData(format!(
            "n_features {n_features} is too large"
        )));
    }
    let expected = n_rows.checked_mul(n_features).ok_or_else(|| {
        ForestError::InvalidData(format!("{n_rows} rows × {n_features} features overflows"))
    })?;
    if x.len() != expected {
        return Err(ForestError::InvalidData(format!(
            "x has {} values, expected {n_rows} rows × {n_features} features = {expected}",
            x.len()
        )));
    }
    if n_rows == 0 {
        return Err(ForestError::InvalidData("the data set is empty".into()));
    }
    if n_rows >= u32::MAX as usize {
        return Err(ForestError::InvalidData(format!(
            "{n_rows} rows is too many (max {})",
            u32::MAX - 1
        )));
    }
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(ForestError::NonFinite {
            row: i / n_features,
            column: i % n_features,
            value: x[i],
        });
    }
    Ok(())
}

/// A classification data set: `n_rows × n_features` features stored row-major, one class index per row.
///
/// Class indices are `0..n_classes`; the class *labels* (e.g. crack widths in mm) live in the models.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    x: Vec<f32>,
    n_features: usize,
    y: Vec<u32>,
    n_classes: usize,
}

impl Dataset {
    /// Builds a data set; `n_classes` is `max(y) + 1`.
    ///
    /// Fails on an empty set, `x.len() != y.len() * n_features`, or a non-finite feature.
    pub fn new(x: Vec<f32>, n_features: usize, y: Vec<u32>) -> Result<Self> {
        let n_classes = y.iter().copied().max().map_or(0, |m| m as usize + 1);
        Self::with_classes(x, n_features, y, n_classes)
    }

    /// Builds a data set with an explicit class count (classes may be absent from `y`).
    pub fn with_classes(
        x: Vec<f32>,
        n_features: usize,
        y: Vec<u32>,
        n_classes: usize,
    ) -> Result<Self> {
        check_features(&x, n_features, y.len())?;
        if n_classes == 0 || n_classes > u16::MAX as usize {
            return Err(ForestError::InvalidData(format!(
                "n_classes {n_classes} out of range 1..=65535"
            )));
        }
        if let Some(i) = y.iter().position(|&c| c as usize >= n_classes) {
            return Err(ForestError::InvalidData(format!(
                "row {i}: class {} is not below n_classes {n_classes}",
                y[i]
            )));
        }
        Ok(Self {
            x,
            n_features,
            y,
            n_classes,
        })
    }

    /// Row-major features.
    pub fn x(&self) -> &[f32] {
        &self.x
    }
    /// Class index per row.
    pub fn y(&self) -> &[u32] {
        &self.y
    }
    /// Number of features per row.
    pub fn n_features(&self) -> usize {
        self.n_features
    }
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.y.len()
    }
    /// Number of classes.
    pub fn n_classes(&self) -> usize {
        self.n_classes
    }
    /// Features of row `i` (`None` when out of range).
    pub fn row(&self, i: usize) -> Option<&[f32]> {
        self.x.get(i * self.n_features..(i + 1) * self.n_features)
    }
    /// The rows with the given indices, as a new data set (same class count). Fails on an out-of-range index
    /// or an empty selection.
    pub fn select(&self, rows: &[usize]) -> Result<Self> {
        let mut x = Vec::with_capacity(rows.len() * self.n_features);
        let mut y = Vec::with_capacity(rows.len());
        for &r in rows {
            let row = self.row(r).ok_or_else(|| {
                ForestError::InvalidData(format!("row {r} out of range ({})", self.n_rows()))
            })?;
            x.extend_from_slice(row);
            y.push(self.y[r]);
        }
        Self::with_classes(x, self.n_features, y, self.n_classes)
    }
    /// Splits into (first `n_first` rows, the rest). Fails if either part would be empty.
    pub fn split_at(&self, n_first: usize) -> Result<(Self, Self)> {
        let a: Vec<usize> = (0..n_first.min(self.n_rows())).collect();
        let b: Vec<usize> = (n_first.min(self.n_rows())..self.n_rows()).collect();
        Ok((self.select(&a)?, self.select(&b)?))
    }
}

/// A regression data set (e.g. crack width in mm): row-major features, one `f32` target per row.
#[derive(Debug, Clone, PartialEq)]
pub struct RegressionDataset {
    x: Vec<f32>,
    n_features: usize,
    y: Vec<f32>,
}

impl RegressionDataset {
    /// Builds a data set; fails on an empty set, mismatched lengths, or non-finite features or targets.
    pub fn new(x: Vec<f32>, n_features: usize, y: Vec<f32>) -> Result<Self> {
        check_features(&x, n_features, y.len())?;
        if let Some(i) = y.iter().position(|v| !v.is_finite()) {
            return Err(ForestError::NonFinite {
                row: i,
                column: n_features,
                value: y[i],
            });
        }
        Ok(Self { x, n_features, y })
    }
    /// Row-major features.
    pub fn x(&self) -> &[f32] {
        &self.x
    }
    /// Target per row.
    pub fn y(&self) -> &[f32] {
        &self.y
    }
    /// Number of features per row.
    pub fn n_features(&self) -> usize {
        self.n_features
    }
    /// Number of rows.
    pub fn n_rows(&self) -> usize {
        self.y.len()
    }
    /// Features of row `i` (`None` when out of range).
    pub fn row(&self, i: usize) -> Option<&[f32]> {
        self.x.get(i * self.n_features..(i + 1) * self.n_features)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dataset_validation() {
        assert!(Dataset::new(vec![1.0, 2.0], 2, vec![0]).is_ok());
        assert!(matches!(
            Dataset::new(vec![], 2, vec![]),
            Err(ForestError::InvalidData(_))
        ));
        assert!(matches!(
            Dataset::new(vec![1.0], 2, vec![0]),
            Err(ForestError::InvalidData(_))
        ));
        assert!(matches!(
            Dataset::new(vec![1.0, 2.0], 0, vec![0]),
            Err(ForestError::InvalidData(_))
        ));
        assert!(matches!(
            Dataset::new(vec![1.0, f32::NAN, 3.0, 4.0], 2, vec![0, 1]),
            Err(ForestError::NonFinite {
                row: 0,
                column: 1,
                ..
            })
        ));
        assert!(matches!(
            Dataset::new(vec![1.0, 2.0, 3.0, f32::INFINITY], 2, vec![0, 1]),
            Err(ForestError::NonFinite {
                row: 1,
                column: 1,
                ..
            })
        ));
        assert!(Dataset::with_classes(vec![1.0], 1, vec![3], 3).is_err());
        let d = Dataset::with_classes(vec![1.0, 2.0], 1, vec![0, 0], 4).unwrap();
        assert_eq!(d.n_classes(), 4);
        assert!(RegressionDataset::new(vec![1.0], 1, vec![f32::NAN]).is_err());
        assert!(RegressionDataset::new(vec![1.0, 2.0], 1, vec![1.0]).is_err());
    }

    #[test]
    fn select_and_split() {
        let d = Dataset::new(vec![1.0, 2.0, 3.0], 1, vec![0, 1, 2]).unwrap();
        let (a, b) = d.split_at(2).unwrap();
        assert_eq!(a.y(), &[0, 1]);
        assert_eq!(b.x(), &[3.0]);
        assert_eq!(b.n_classes(), 3);
        assert!(d.select(&[5]).is_err());
        assert!(d.split_at(3).is_err());
    }
}
