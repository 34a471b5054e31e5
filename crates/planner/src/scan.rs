//! The paper's eq. 2, `N_s = h / (γ·L̄) + 1`, and its Table II.

use serde::Serialize;

use crate::error::{positive, PlanError};
use crate::MAX_SCAN_ROWS;

/// `h / (γ·L̄) + 1`, unrounded (`h` and `L̄` in the same unit). Errors unless `h` and `L̄` are
/// finite and positive and `0 < γ < 1`.
pub fn scan_rows_exact(h: f64, gamma: f64, mean_length: f64) -> Result<f64, PlanError> {
    positive("h", h)?;
    positive("mean_length", mean_length)?;
    if !(gamma.is_finite() && gamma > 0.0 && gamma < 1.0) {
        return Err(PlanError::InvalidParam {
            field: "gamma".into(),
            value: gamma,
            expected: "in the open interval (0, 1) (eq. 2's design parameter)",
        });
    }
    Ok(h / (gamma * mean_length) + 1.0)
}

/// Eq. 2: the number of scan rows `N_s = ⌊h / (γ·L̄)⌋ + 1`: rows `γ·L̄` apart or closer from
/// one edge of the height `h` to the other. The paper's Table II rounds the same way:
/// `480 / (γ · 148.06) + 1` = 13.97, 7.48, 5.32 for γ = 0.25, 0.5, 0.75, and it ran 13, 7 and 5
/// rows. Errors as [`scan_rows_exact`], and beyond [`MAX_SCAN_ROWS`] rows.
pub fn scan_rows_count(h: f64, gamma: f64, mean_length: f64) -> Result<usize, PlanError> {
    let exact = scan_rows_exact(h, gamma, mean_length)?;
    let rows = exact.floor();
    if rows > MAX_SCAN_ROWS as f64 {
        return Err(PlanError::TooManyRows {
            rows,
            height_mm: h,
            spacing_mm: gamma * mean_length,
            max: MAX_SCAN_ROWS,
        });
    }
    Ok(rows as usize)
}

/// `L̄` in millimetres the way the paper's eq. 2 implies: a crack of `L̄` pixels in the dataset
/// images is taken to be `L̄` pixels of a camera frame `camera_height_px` tall that spans the
/// workspace height (the paper divides its 480 px camera height by the 148.06 px length
/// measured on 227 × 227 dataset images).
pub fn paper_mean_length_mm(
    mean_length_px: f64,
    camera_height_px: f64,
    workspace_height_mm: f64,
) -> f64 {
    mean_length_px / camera_height_px * workspace_height_mm
}

/// One row of the paper's Table II: time to explore the 200 × 100 mm surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperTimeRow {
    /// γ (tactile only), `None` for tactile + vision.
    pub gamma: Option<f64>,
    /// `N_s`, `None` for tactile + vision.
    pub rows: Option<usize>,
    /// Mean time, s.
    pub time_s: f64,
    /// Its standard deviation, s.
    pub sd_s: f64,
}

/// The paper's Table II: tactile only with γ = 0.25, 0.5, 0.75, then tactile + vision.
pub const PAPER_TABLE_II: [PaperTimeRow; 4] = [
    PaperTimeRow {
        gamma: Some(0.25),
        rows: Some(13),
        time_s: 519.40,
        sd_s: 24.90,
    },
    PaperTimeRow {
        gamma: Some(0.50),
        rows: Some(7),
        time_s: 278.61,
        sd_s: 16.58,
    },
    PaperTimeRow {
        gamma: Some(0.75),
        rows: Some(5),
        time_s: 198.56,
        sd_s: 8.06,
    },
    PaperTimeRow {
        gamma: None,
        rows: None,
        time_s: 31.85,
        sd_s: 1.91,
    },
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PAPER_EQ1;

    #[test]
    fn eq2_gives_the_papers_rows() {
        for row in &PAPER_TABLE_II[..3] {
            let g = row.gamma.unwrap();
            let n =
                scan_rows_count(PAPER_EQ1.camera_height_px, g, PAPER_EQ1.mean_length_px).unwrap();
            assert_eq!(Some(n), row.rows, "γ = {g}");
            // Scale invariance: the same in millimetres under the paper's mapping.
            let l_mm =
                paper_mean_length_mm(PAPER_EQ1.mean_length_px, PAPER_EQ1.camera_height_px, 100.0);
            assert_eq!(scan_rows_count(100.0, g, l_mm).unwrap(), n);
        }
    }

    #[test]
    fn gamma_and_lengths_are_checked() {
        for g in [0.0, 1.0, -0.5, 1.5, f64::NAN, f64::INFINITY] {
            let e = scan_rows_count(100.0, g, 30.0).unwrap_err();
            assert!(e.to_string().contains("gamma"), "{e}");
        }
        assert!(scan_rows_count(0.0, 0.5, 30.0)
            .unwrap_err()
            .to_string()
            .contains("h must"));
        assert!(scan_rows_count(100.0, 0.5, 0.0)
            .unwrap_err()
            .to_string()
            .contains("mean_length"));
        assert!(matches!(
            scan_rows_count(1e9, 0.5, 1e-3),
            Err(PlanError::TooManyRows { .. })
        ));
        // A crack longer than the height: one row, or two when γ·L̄ ≤ h.
        assert_eq!(scan_rows_count(100.0, 0.5, 300.0).unwrap(), 1);
        assert_eq!(scan_rows_count(100.0, 0.5, 200.0).unwrap(), 2);
    }
}
