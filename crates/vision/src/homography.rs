//! Pixel ↔ work-surface millimetres through a plane homography, fitted from point pairs.
//!
//! Conventions:
//! * Pixels are `(u, v)`: u right, v down, origin at the top-left corner of the top-left pixel
//!   (the convention of [`crate::Detector`]).
//! * Surface points are `(x, y)` in millimetres in the work-surface frame.
//! * [`Homography`] holds the 3×3 matrix `H` with `(x, y, 1)ᵀ ~ H (u, v, 1)ᵀ` (pixel → surface)
//!   and its inverse; it is stored scaled so that `H[2][2] = 1` when that is possible. It, its
//!   application to points ([`apply_finite`]: negative `w` allowed, `|w|` near zero is at
//!   infinity), [`PointPair`] and [`ReprojectionStats`] are
//!   defined in `crackbot_imaging::homography` and re-exported here.
//! * Fitting is the normalised DLT (Hartley): each side is translated so its centroid is at the
//!   origin and scaled so the mean distance from it is √2, the 2n×9 system is solved by SVD, and
//!   the result is denormalised. [`fit_ransac`] adds robustness to gross outliers.
//! * Reprojection errors are reported on the surface side in mm (`|H(pixel) − surface|`) and on
//!   the image side in px (`|H⁻¹(surface) − pixel|`).
//! * Degenerate input (fewer than 4 pairs, non-finite values, duplicate points, (almost) all points
//!   on one line, an ill-conditioned system, a fit that sends an input point to infinity) is
//!   rejected with [`VisionError::Homography`]; nothing here panics on user data.

use std::path::Path;

use crackbot_imaging::homography::{apply_finite, normalisation, INFINITY_EPS};
pub use crackbot_imaging::homography::{Homography, PointPair, ReprojectionStats};
use nalgebra::{DMatrix, Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::VisionError;

/// Relative tolerance under which points are "the same" or "on one line" (relative to the spread
/// of the points).
const GEOMETRY_EPS: f64 = 1e-9;
/// The second-smallest singular value of the normalised DLT system, relative to the largest,
/// below which the solution is not unique (ill-conditioned / degenerate configuration).
const CONDITION_EPS: f64 = 1e-7;

fn invalid(message: impl Into<String>) -> VisionError {
    VisionError::Homography {
        reason: message.into(),
    }
}

/// Spread of a point set (RMS distance from its centroid) and its two principal standard
/// deviations (largest first).
fn principal_spread(points: &[[f64; 2]]) -> (f64, f64) {
    let n = points.len() as f64;
    let cx = points.iter().map(|p| p[0]).sum::<f64>() / n;
    let cy = points.iter().map(|p| p[1]).sum::<f64>() / n;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p[0] - cx, p[1] - cy);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let (sxx, sxy, syy) = (sxx / n, sxy / n, syy / n);
    let tr = sxx + syy;
    let disc = ((sxx - syy) * (sxx - syy) / 4.0 + sxy * sxy).sqrt();
    let l1 = tr / 2.0 + disc;
    let l2 = (tr / 2.0 - disc).max(0.0);
    (l1.sqrt(), l2.sqrt())
}

/// Checks one side of the pairs: finite, distinct, not (all but at most one) on one line.
fn check_side(points: &[[f64; 2]], side: &str) -> Result<(), VisionError> {
    for (i, p) in points.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(invalid(format!("{side} point {i} is not finite: {p:?}")));
        }
    }
    let (major, minor) = principal_spread(points);
    let scale = major.max(f64::MIN_POSITIVE);
    let tol = GEOMETRY_EPS * scale;
    // Duplicates: sort by x and compare neighbours within the tolerance window.
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| points[a][0].total_cmp(&points[b][0]));
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if points[j][0] - points[i][0] > tol {
                break;
            }
            if (points[j][1] - points[i][1]).abs() <= tol {
                return Err(invalid(format!(
                    "{side} points {} and {} are the same point {:?}",
                    i.min(j),
                    i.max(j),
                    points[i]
                )));
            }
        }
    }
    if minor <= GEOMETRY_EPS * scale {
        return Err(invalid(format!("all {side} points lie on one line")));
    }
    // All but one on a line: then no 4 of them are in general position.
    let mut rest = Vec::with_capacity(points.len() - 1);
    for skip in 0..points.len() {
        rest.clear();
        rest.extend(
            points
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != skip)
                .map(|(_, p)| *p),
        );
        let (_, minor) = principal_spread(&rest);
        if minor <= GEOMETRY_EPS * scale {
            return Err(invalid(format!(
                "all {side} points but point {skip} lie on one line: no 4 points in general position"
            )));
        }
    }
    Ok(())
}

/// Points of one side of the pairs.
type Points = Vec<[f64; 2]>;

/// The pixel and surface points of `pairs`, once both sides are checked (at least 4 pairs, see
/// `check_side`).
fn checked_sides(pairs: &[PointPair]) -> Result<(Points, Points), VisionError> {
    if pairs.len() < 4 {
        return Err(invalid(format!(
            "a homography needs at least 4 point pairs, got {}",
            pairs.len()
        )));
    }
    let pixels: Vec<[f64; 2]> = pairs.iter().map(|p| p.pixel).collect();
    let surface: Vec<[f64; 2]> = pairs.iter().map(|p| p.surface).collect();
    check_side(&pixels, "pixel")?;
    check_side(&surface, "surface")?;
    Ok((pixels, surface))
}

/// Fits the pixel → surface homography to `pairs` by the normalised DLT (least squares in the
/// algebraic sense; exact for 4 pairs). See the module docs for what is rejected.
pub fn fit_dlt(pairs: &[PointPair]) -> Result<Homography, VisionError> {
    let (pixels, surface) = checked_sides(pairs)?;
    fit_unchecked(&pixels, &surface)
}

fn fit_unchecked(pixels: &[[f64; 2]], surface: &[[f64; 2]]) -> Result<Homography, VisionError> {
    let tp = normalisation(pixels).ok_or_else(|| invalid("all pixel points coincide"))?;
    let ts = normalisation(surface).ok_or_else(|| invalid("all surface points coincide"))?;
    let n = pixels.len();
    // At least 9 rows so that the SVD yields all 9 right singular vectors.
    let rows = (2 * n).max(9);
    let mut a = DMatrix::<f64>::zeros(rows, 9);
    let mut np = Vec::with_capacity(n);
    for (i, (p, s)) in pixels.iter().zip(surface).enumerate() {
        let p = tp * Vector3::new(p[0], p[1], 1.0);
        let s = ts * Vector3::new(s[0], s[1], 1.0);
        let (u, v) = (p.x, p.y);
        let (x, y) = (s.x, s.y);
        let r0 = [0.0, 0.0, 0.0, -u, -v, -1.0, y * u, y * v, y];
        let r1 = [u, v, 1.0, 0.0, 0.0, 0.0, -x * u, -x * v, -x];
        for c in 0..9 {
            a[(2 * i, c)] = r0[c];
            a[(2 * i + 1, c)] = r1[c];
        }
        np.push(p);
    }
    let svd = a.svd(false, true);
    let v_t = svd
        .v_t
        .ok_or_else(|| invalid("SVD of the homography system failed"))?;
    let sv = svd.singular_values;
    if sv.iter().any(|s| !s.is_finite()) {
        return Err(invalid(
            "SVD of the homography system failed (non-finite values)",
        ));
    }
    // Sorted descending by nalgebra; do not rely on it.
    let mut order: Vec<usize> = (0..sv.len()).collect();
    order.sort_by(|&i, &j| sv[j].total_cmp(&sv[i]));
    let (largest, second_smallest, smallest) = (sv[order[0]], sv[order[7]], sv[order[8]]);
    let unique = second_smallest > CONDITION_EPS * largest;
    if !unique {
        return Err(invalid(format!(
            "ill-conditioned homography system (singular values: largest {largest:.3e}, two smallest \
             {second_smallest:.3e} and {smallest:.3e}): the points do not determine a unique homography"
        )));
    }
    let h = v_t.row(order[8]);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    // Every input point must map to a finite point, all on the same side of the vanishing line.
    let ws: Vec<f64> = np.iter().map(|p| (hn * p).z).collect();
    let wscale = hn.row(2).abs().sum() * 3.0;
    if let Some(i) = ws.iter().position(|w| {
        let finite_point = w.abs() > INFINITY_EPS * wscale;
        !finite_point
    }) {
        return Err(invalid(format!(
            "the fitted homography maps pixel {:?} to infinity",
            pixels[i]
        )));
    }
    if ws.iter().any(|w| w.signum() != ws[0].signum()) {
        return Err(invalid(
            "the fitted homography puts input points on both sides of the vanishing line (points \
             mismatched or not from one plane)",
        ));
    }
    let ts_inv = ts
        .try_inverse()
        .ok_or_else(|| invalid("surface normalisation is singular"))?;
    Ok(Homography::from_nalgebra(ts_inv * hn * tp)?)
}

/// A RANSAC fit: the homography refitted on the inliers, and which pairs are inliers.
#[derive(Debug, Clone, PartialEq)]
pub struct RansacFit {
    /// The model refitted (normalised DLT) on all inliers.
    pub homography: Homography,
    /// `inliers[i]`: pair `i` is within the threshold of the final model.
    pub inliers: Vec<bool>,
}

impl RansacFit {
    /// Number of inliers.
    pub fn inlier_count(&self) -> usize {
        self.inliers.iter().filter(|&&b| b).count()
    }
}

fn triangle_degenerate(a: [f64; 2], b: [f64; 2], c: [f64; 2], scale: f64) -> bool {
    let cross = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    cross.abs() <= 1e-6 * scale * scale
}

fn sample_degenerate(points: &[[f64; 2]; 4], scale: f64) -> bool {
    let [a, b, c, d] = *points;
    triangle_degenerate(a, b, c, scale)
        || triangle_degenerate(a, b, d, scale)
        || triangle_degenerate(a, c, d, scale)
        || triangle_degenerate(b, c, d, scale)
}

fn inliers_of(h: &Homography, pairs: &[PointPair], threshold_mm: f64) -> (Vec<bool>, f64) {
    let mut total = 0.0;
    let mask = pairs
        .iter()
        .map(|p| match apply_finite(h.forward(), p.pixel) {
            Some(s) => {
                let e = (s[0] - p.surface[0]).hypot(s[1] - p.surface[1]);
                let inlier = e <= threshold_mm;
                if inlier {
                    total += e;
                }
                inlier
            }
            None => false,
        })
        .collect();
    (mask, total)
}

/// Robust fit: `iterations` random minimal samples of 4 pairs (seeded, deterministic), the model
/// with the most pairs within `threshold_mm` (surface-side error) wins, then it is refitted on its
/// inliers by [`fit_dlt`] (repeated while the inlier set grows, at most 10 times).
///
/// Errors on degenerate input (as [`fit_dlt`]), a non-positive threshold, zero iterations, or when
/// no sample yields a model with at least 5 inliers (4 when only 4 pairs are given: any 4 pairs
/// fit exactly, so a consensus needs a fifth).
pub fn fit_ransac(
    pairs: &[PointPair],
    threshold_mm: f64,
    iterations: usize,
    seed: u64,
) -> Result<RansacFit, VisionError> {
    let usable = threshold_mm > 0.0 && threshold_mm.is_finite();
    if !usable {
        return Err(VisionError::setting(
            "RANSAC threshold_mm",
            threshold_mm,
            "a positive number of mm",
        ));
    }
    if iterations == 0 {
        return Err(VisionError::setting("RANSAC iterations", 0.0, "≥ 1"));
    }
    let (pixels, surface) = checked_sides(pairs)?;
    let pixel_scale = principal_spread(&pixels).0;
    let surface_scale = principal_spread(&surface).0;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = pairs.len();
    let mut best: Option<(usize, f64, Vec<bool>)> = None;
    for _ in 0..iterations {
        let mut idx = [0usize; 4];
        let mut k = 0;
        while k < 4 {
            let c = rng.random_range(0..n);
            if !idx[..k].contains(&c) {
                idx[k] = c;
                k += 1;
            }
        }
        let sp = idx.map(|i| pixels[i]);
        let ss = idx.map(|i| surface[i]);
        if sample_degenerate(&sp, pixel_scale) || sample_degenerate(&ss, surface_scale) {
            continue;
        }
        let Ok(h) = fit_unchecked(&sp, &ss) else {
            continue;
        };
        let (mask, total) = inliers_of(&h, pairs, threshold_mm);
        let count = mask.iter().filter(|&&b| b).count();
        let better = match &best {
            None => true,
            Some((c, t, _)) => count > *c || (count == *c && total < *t),
        };
        if better {
            best = Some((count, total, mask));
        }
    }
    let Some((count, _, mut mask)) = best else {
        return Err(invalid("RANSAC found no non-degenerate sample of 4 pairs"));
    };
    // Any 4 pairs fit exactly: a consensus needs a fifth pair (unless only 4 were given).
    let needed = n.min(5);
    if count < needed {
        return Err(invalid(format!(
            "RANSAC found no model with {needed} or more inliers within {threshold_mm} mm"
        )));
    }
    let subset = |mask: &[bool]| -> Vec<PointPair> {
        pairs
            .iter()
            .zip(mask)
            .filter(|(_, &m)| m)
            .map(|(p, _)| *p)
            .collect()
    };
    let mut homography = fit_dlt(&subset(&mask))?;
    for _ in 0..10 {
        let (new_mask, _) = inliers_of(&homography, pairs, threshold_mm);
        let new_count = new_mask.iter().filter(|&&b| b).count();
        if new_count <= mask.iter().filter(|&&b| b).count() || new_mask == mask {
            break;
        }
        match fit_dlt(&subset(&new_mask)) {
            Ok(h) => {
                homography = h;
                mask = new_mask;
            }
            Err(_) => break,
        }
    }
    let (inliers, _) = inliers_of(&homography, pairs, threshold_mm);
    Ok(RansacFit {
        homography,
        inliers,
    })
}

/// A homography calibration file (TOML): the point pairs it was fitted on, the fitted matrix, and
/// its reprojection errors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HomographyCalibration {
    /// Image-side unit, always `"px"`.
    pub pixel_units: String,
    /// Surface-side unit, always `"mm"`.
    pub surface_units: String,
    /// Row-major pixel → surface matrix.
    pub matrix: [[f64; 3]; 3],
    /// RMS surface-side reprojection error of `pairs`, mm.
    pub rms_mm: f64,
    /// Largest surface-side reprojection error of `pairs`, mm.
    pub max_mm: f64,
    /// RMS image-side reprojection error of `pairs`, px.
    pub rms_px: f64,
    /// Largest image-side reprojection error of `pairs`, px.
    pub max_px: f64,
    /// The pairs the matrix was fitted on (after outlier rejection, if any).
    pub pairs: Vec<PointPair>,
}

impl HomographyCalibration {
    /// A calibration from a homography and the pairs it was fitted on (errors computed here).
    pub fn new(homography: &Homography, pairs: Vec<PointPair>) -> Self {
        let stats = homography.reprojection_errors(&pairs);
        Self {
            pixel_units: "px".into(),
            surface_units: "mm".into(),
            matrix: homography.matrix(),
            rms_mm: stats.rms_mm,
            max_mm: stats.max_mm,
            rms_px: stats.rms_px,
            max_px: stats.max_px,
            pairs,
        }
    }

    /// Fits [`fit_dlt`] on `pairs` and records the result.
    pub fn fit(pairs: Vec<PointPair>) -> Result<Self, VisionError> {
        let h = fit_dlt(&pairs)?;
        Ok(Self::new(&h, pairs))
    }

    /// The homography of the calibration (validated).
    pub fn homography(&self) -> Result<Homography, VisionError> {
        Ok(Homography::from_matrix(self.matrix)?)
    }

    /// Checks units, finiteness, invertibility, that the pairs are usable, and that the matrix and
    /// recorded errors agree with the pairs. `path` is only used in error messages.
    pub fn validate(&self, path: &Path) -> Result<Homography, VisionError> {
        let err = |message: String| VisionError::Calibration {
            path: path.to_path_buf(),
            message,
        };
        if self.pixel_units != "px" || self.surface_units != "mm" {
            return Err(err(format!(
                "units must be px and mm, found {} and {}",
                self.pixel_units, self.surface_units
            )));
        }
        let h = self.homography().map_err(|e| err(e.to_string()))?;
        for (name, v) in [
            ("rms_mm", self.rms_mm),
            ("max_mm", self.max_mm),
            ("rms_px", self.rms_px),
            ("max_px", self.max_px),
        ] {
            if !v.is_finite() || v < 0.0 {
                return Err(err(format!(
                    "{name} must be a finite non-negative number, found {v}"
                )));
            }
        }
        if self.pairs.len() < 4 {
            return Err(err(format!(
                "needs at least 4 point pairs, found {}",
                self.pairs.len()
            )));
        }
        let pixels: Vec<[f64; 2]> = self.pairs.iter().map(|p| p.pixel).collect();
        let surface: Vec<[f64; 2]> = self.pairs.iter().map(|p| p.surface).collect();
        check_side(&pixels, "pixel").map_err(|e| err(e.to_string()))?;
        check_side(&surface, "surface").map_err(|e| err(e.to_string()))?;
        let stats = h.reprojection_errors(&self.pairs);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 + 1e-6 * b.abs();
        if !(close(stats.rms_mm, self.rms_mm)
            && close(stats.max_mm, self.max_mm)
            && close(stats.rms_px, self.rms_px)
            && close(stats.max_px, self.max_px))
        {
            return Err(err(format!(
                "matrix does not match the point pairs: recomputed RMS {:.6} mm / max {:.6} mm / RMS \
                 {:.6} px / max {:.6} px, recorded {:.6} / {:.6} / {:.6} / {:.6}",
                stats.rms_mm,
                stats.max_mm,
                stats.rms_px,
                stats.max_px,
                self.rms_mm,
                self.max_mm,
                self.rms_px,
                self.max_px
            )));
        }
        Ok(h)
    }

    /// Reads and validates a calibration file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, VisionError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(VisionError::io(path))?;
        let cal: Self = toml::from_str(&text).map_err(|e| VisionError::Calibration {
            path: path.to_path_buf(),
            message: format!("not a homography calibration: {e}"),
        })?;
        cal.validate(path)?;
        Ok(cal)
    }

    /// Writes the calibration as TOML.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), VisionError> {
        let path = path.as_ref();
        let text = toml::to_string_pretty(self).map_err(|e| VisionError::Calibration {
            path: path.to_path_buf(),
            message: format!("cannot encode: {e}"),
        })?;
        std::fs::write(path, text).map_err(VisionError::io(path))
    }
}

/// RANSAC settings for [`fit_calibration`] (see [`fit_ransac`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RansacSettings {
    /// Surface-side inlier threshold, mm.
    pub threshold_mm: f64,
    /// Random minimal samples drawn.
    pub iterations: usize,
    /// Seed of the sampling.
    pub seed: u64,
}

/// A calibration fitted to point pairs ([`fit_calibration`]).
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationFit {
    /// The calibration, holding the pairs it kept (all of them without RANSAC, the inliers
    /// with it).
    pub calibration: HomographyCalibration,
    /// Pairs given.
    pub pairs_given: usize,
    /// The RANSAC settings used, if any.
    pub ransac: Option<RansacSettings>,
}

/// Fits a calibration to `pairs`: [`fit_dlt`] on all of them, or with `ransac`, [`fit_ransac`]
/// keeping only its inliers.
pub fn fit_calibration(
    pairs: Vec<PointPair>,
    ransac: Option<RansacSettings>,
) -> Result<CalibrationFit, VisionError> {
    let pairs_given = pairs.len();
    let calibration = match ransac {
        Some(r) => {
            let fit = fit_ransac(&pairs, r.threshold_mm, r.iterations, r.seed)?;
            let kept: Vec<PointPair> = pairs
                .iter()
                .zip(&fit.inliers)
                .filter(|(_, &inlier)| inlier)
                .map(|(p, _)| *p)
                .collect();
            HomographyCalibration::new(&fit.homography, kept)
        }
        None => HomographyCalibration::new(&fit_dlt(&pairs)?, pairs),
    };
    Ok(CalibrationFit {
        calibration,
        pairs_given,
        ransac,
    })
}

/// Reads point pairs from a CSV file: `u,v,x_mm,y_mm` per line (pixel column and row, surface x
/// and y in mm). Blank lines and lines starting with `#` are skipped, and so is a first line
/// that is not four numbers (a header). Any other line that is not four numbers is an error
/// naming the file and the line.
pub fn read_pairs(path: impl AsRef<Path>) -> Result<Vec<PointPair>, VisionError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(VisionError::io(path))?;
    parse_pairs(&text, path)
}

/// Parses the text of a point-pairs file (see [`read_pairs`]); `path` is only used in error
/// messages.
pub fn parse_pairs(text: &str, path: &Path) -> Result<Vec<PointPair>, VisionError> {
    let mut pairs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let nums: Result<Vec<f64>, _> = line
            .split(',')
            .map(str::trim)
            .map(str::parse::<f64>)
            .collect();
        match nums {
            Ok(n) if n.len() == 4 => pairs.push(PointPair::new([n[0], n[1]], [n[2], n[3]])),
            Err(_) if i == 0 => {} // header
            _ => {
                return Err(VisionError::PointPairs {
                    path: path.to_path_buf(),
                    line: i + 1,
                    message: format!("expected 4 numbers u,v,x_mm,y_mm, got {line:?}"),
                })
            }
        }
    }
    Ok(pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_files_skip_a_header_and_name_bad_lines() {
        let p = Path::new("pairs.csv");
        let pairs = parse_pairs("u,v,x_mm,y_mm\n\n# comment\n1, 2, 3, 4\n5,6,7,8\n", p).unwrap();
        assert_eq!(
            pairs,
            vec![
                PointPair::new([1.0, 2.0], [3.0, 4.0]),
                PointPair::new([5.0, 6.0], [7.0, 8.0])
            ]
        );
        let err = parse_pairs("1,2,3,4\n1,2,3\n", p).unwrap_err();
        assert_eq!(
            err.to_string(),
            "pairs.csv line 2: expected 4 numbers u,v,x_mm,y_mm, got \"1,2,3\""
        );
        assert!(read_pairs("no/such/pairs.csv").is_err());
    }

    #[test]
    fn a_calibration_fit_keeps_all_pairs_or_the_ransac_inliers() {
        let mut pairs: Vec<PointPair> = (0..5)
            .flat_map(|i| (0..4).map(move |j| (f64::from(i) * 50.0, f64::from(j) * 30.0)))
            .map(|(x, y)| {
                let w = 1.0 + 0.001 * x + 0.0005 * y;
                PointPair::new([(2.0 * x + 10.0) / w, (2.0 * y + 5.0) / w], [x, y])
            })
            .collect();
        let all = fit_calibration(pairs.clone(), None).unwrap();
        assert_eq!((all.calibration.pairs.len(), all.pairs_given), (20, 20));
        assert!(all.ransac.is_none());
        pairs.push(PointPair::new([5.0, 5.0], [180.0, 70.0]));
        let settings = RansacSettings {
            threshold_mm: 0.5,
            iterations: 500,
            seed: 1,
        };
        let fit = fit_calibration(pairs, Some(settings)).unwrap();
        assert_eq!((fit.calibration.pairs.len(), fit.pairs_given), (20, 21));
        assert!(fit.calibration.max_mm < 1e-6, "{}", fit.calibration.max_mm);
    }
}
