//! Statistics for comparing results: mean ± standard deviation and the Kruskal–Wallis H test
//! the paper uses across feature sets.

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::TactileError;

/// Mean and sample standard deviation (n − 1; 0 for a single value, NaN when empty).
pub fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return (mean, 0.0);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, var.sqrt())
}

/// Result of a Kruskal–Wallis H test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct KruskalWallis {
    /// H statistic, corrected for ties (as `scipy.stats.kruskal`).
    pub h: f64,
    /// p-value from the χ² distribution with `dof` degrees of freedom.
    pub p: f64,
    /// Groups − 1.
    pub dof: usize,
}

/// Kruskal–Wallis H test of whether the groups come from the same distribution.
/// Needs at least two non-empty groups of finite values, not all equal.
pub fn kruskal_wallis(groups: &[&[f64]]) -> Result<KruskalWallis, TactileError> {
    if groups.len() < 2 || groups.iter().any(|g| g.is_empty()) {
        return Err(TactileError::Statistics {
            reason: "Kruskal–Wallis needs at least two non-empty groups".into(),
        });
    }
    let mut all: Vec<(f64, usize)> = Vec::new();
    for (g, values) in groups.iter().enumerate() {
        for &v in *values {
            if !v.is_finite() {
                return Err(TactileError::Statistics {
                    reason: format!("Kruskal–Wallis: non-finite value {v} in group {g}"),
                });
            }
            all.push((v, g));
        }
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let n = all.len() as f64;
    let mut rank_sums = vec![0.0; groups.len()];
    let mut tie_term = 0.0;
    let mut i = 0;
    while i < all.len() {
        let mut j = i;
        while j + 1 < all.len() && all[j + 1].0 == all[i].0 {
            j += 1;
        }
        let rank = (i + j) as f64 / 2.0 + 1.0; // mean of ranks i+1 ..= j+1
        for item in &all[i..=j] {
            rank_sums[item.1] += rank;
        }
        let t = (j - i + 1) as f64;
        tie_term += t * t * t - t;
        i = j + 1;
    }
    let h0 = 12.0 / (n * (n + 1.0))
        * groups
            .iter()
            .zip(&rank_sums)
            .map(|(g, r)| r * r / g.len() as f64)
            .sum::<f64>()
        - 3.0 * (n + 1.0);
    let correction = 1.0 - tie_term / (n * n * n - n);
    if correction <= 0.0 {
        return Err(TactileError::Statistics {
            reason: "Kruskal–Wallis: all values are equal".into(),
        });
    }
    let h = h0 / correction;
    let dof = groups.len() - 1;
    let chi2 = ChiSquared::new(dof as f64).map_err(|e| TactileError::Statistics {
        reason: e.to_string(),
    })?;
    Ok(KruskalWallis {
        h,
        p: chi2.sf(h),
        dof,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    // Reference values from scipy.stats.kruskal's documented examples.
    #[test]
    fn matches_scipy_examples() {
        let r = kruskal_wallis(&[&[1.0, 3.0, 5.0, 7.0, 9.0], &[2.0, 4.0, 6.0, 8.0, 10.0]]).unwrap();
        assert!((r.h - 0.2727272727272734).abs() < 1e-12, "{r:?}");
        assert!((r.p - 0.6015081344405895).abs() < 1e-12, "{r:?}");
        let r = kruskal_wallis(&[&[1.0, 1.0, 1.0], &[2.0, 2.0, 2.0], &[2.0, 2.0]]).unwrap();
        assert!((r.h - 7.0).abs() < 1e-12, "{r:?}");
        assert!((r.p - 0.0301973834223185).abs() < 1e-12, "{r:?}");
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        assert!(kruskal_wallis(&[&[1.0, 2.0]]).is_err());
        assert!(kruskal_wallis(&[&[1.0], &[]]).is_err());
        assert!(kruskal_wallis(&[&[1.0, 1.0], &[1.0]]).is_err());
        assert!(kruskal_wallis(&[&[1.0, f64::NAN], &[2.0]]).is_err());
    }

    #[test]
    fn mean_and_std() {
        let (m, s) = mean_std(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert!((m - 5.0).abs() < 1e-12);
        assert!((s - 2.138089935299395).abs() < 1e-12);
        assert_eq!(mean_std(&[3.0]), (3.0, 0.0));
    }
}
