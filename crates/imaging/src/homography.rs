//! Plane homographies between image pixels and surface millimetres: applying one to a point, and
//! the validated pixel → surface [`Homography`].
//!
//! Conventions:
//! * Pixels are `(u, v)`: u right, v down, origin at the top-left corner of the top-left pixel
//!   (pixel `(col, row)` covers `[col, col + 1) × [row, row + 1)`).
//! * Surface points are `(x, y)` in millimetres in the work surface's (the plate's) frame.
//! * A homography `H` maps `p` to `(q_x / q_w, q_y / q_w)` with `q = H (p_x, p_y, 1)ᵀ`.
//!
//! Where `q_w` is (nearly) zero the point maps to infinity, and what counts as "nearly" depends on
//! where the matrix comes from; crackbot uses two policies:
//! * [`apply_in_front`], for a camera's exact plate ↔ image homography (built so that `q_w` is
//!   the depth in front of the camera): `q_w ≤ 1e-12` (absolute) or NaN is at or behind the
//!   horizon, and has no image.
//! * [`apply_finite`], for a homography fitted to point pairs (whose overall sign is
//!   arbitrary): negative `q_w` is accepted, `|q_w| ≤ 1e-9 · Σ|H₂ⱼ| · (1 + |p_x| + |p_y|)` is at
//!   infinity, and so is a non-finite result.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::ImagingError;

/// [`apply_in_front`]: `q_w` at or below this (absolute) is at or behind the horizon.
pub const IN_FRONT_EPS: f64 = 1e-12;

/// [`apply_finite`]: `|q_w|` at or below this, relative to the matrix's last row and the
/// point's size, is at infinity.
pub const INFINITY_EPS: f64 = 1e-9;

/// Applies a camera's homography `h` to `p`: `None` at or beyond the horizon (`w ≤ 1e-12` or
/// NaN). Cheap enough for per-pixel loops (no allocation, no generic
/// matrix code).
#[inline]
pub fn apply_in_front(h: &Matrix3<f64>, p: [f64; 2]) -> Option<[f64; 2]> {
    let [u, v] = p;
    let w = h[(2, 0)] * u + h[(2, 1)] * v + h[(2, 2)];
    if w.is_nan() || w <= IN_FRONT_EPS {
        return None;
    }
    Some([
        (h[(0, 0)] * u + h[(0, 1)] * v + h[(0, 2)]) / w,
        (h[(1, 0)] * u + h[(1, 1)] * v + h[(1, 2)]) / w,
    ])
}

/// Applies a fitted homography `h` to `p`: `None` when the point maps to infinity (relative to
/// the matrix and the point) or to a non-finite point.
#[inline]
pub fn apply_finite(h: &Matrix3<f64>, p: [f64; 2]) -> Option<[f64; 2]> {
    let r = h * Vector3::new(p[0], p[1], 1.0);
    let scale = h.row(2).abs().sum() * (1.0 + p[0].abs() + p[1].abs());
    let finite_point = r.z.abs() > INFINITY_EPS * scale;
    if !finite_point {
        return None;
    }
    let out = [r.x / r.z, r.y / r.z];
    (out[0].is_finite() && out[1].is_finite()).then_some(out)
}

/// Hartley normalisation of a point set: `T` that moves the centroid to the origin and scales the
/// mean distance from it to √2 (the conditioning step of a normalised DLT). `None` when all
/// points coincide or a coordinate is not finite.
pub fn normalisation(points: &[[f64; 2]]) -> Option<Matrix3<f64>> {
    let n = points.len() as f64;
    let cx = points.iter().map(|p| p[0]).sum::<f64>() / n;
    let cy = points.iter().map(|p| p[1]).sum::<f64>() / n;
    let mean = points
        .iter()
        .map(|p| (p[0] - cx).hypot(p[1] - cy))
        .sum::<f64>()
        / n;
    if !(mean > 0.0 && mean.is_finite()) {
        return None;
    }
    let s = std::f64::consts::SQRT_2 / mean;
    Some(Matrix3::new(
        s,
        0.0,
        -s * cx,
        0.0,
        s,
        -s * cy,
        0.0,
        0.0,
        1.0,
    ))
}

/// A 3 × 3 matrix as row-major arrays.
pub fn matrix_rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

/// One correspondence: a pixel and the surface point it shows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointPair {
    /// `(u, v)` in pixels.
    pub pixel: [f64; 2],
    /// `(x, y)` in millimetres on the surface.
    pub surface: [f64; 2],
}

impl PointPair {
    /// A pair from pixel `(u, v)` and surface `(x, y)`.
    pub fn new(pixel: [f64; 2], surface: [f64; 2]) -> Self {
        Self { pixel, surface }
    }
}

/// A plane homography from pixels to surface millimetres, with its inverse, applied with the
/// [`apply_finite`] policy. Stored scaled so that `H[2][2] = 1` when that is possible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Homography {
    forward: Matrix3<f64>,
    inverse: Matrix3<f64>,
}

fn invalid(message: impl Into<String>) -> ImagingError {
    ImagingError::Homography(message.into())
}

impl Homography {
    /// A homography from its row-major pixel → surface matrix. Errors when the matrix is not finite
    /// or not invertible.
    pub fn from_matrix(matrix: [[f64; 3]; 3]) -> Result<Self, ImagingError> {
        if matrix.iter().flatten().any(|v| !v.is_finite()) {
            return Err(invalid(format!(
                "homography matrix has non-finite entries: {matrix:?}"
            )));
        }
        let m = Matrix3::from_fn(|r, c| matrix[r][c]);
        Self::from_nalgebra(m)
    }

    /// A homography from its pixel → surface matrix. Errors when the matrix is singular or nearly
    /// so (smallest over largest singular value ≤ 1e-12) or its inverse is not finite.
    pub fn from_nalgebra(m: Matrix3<f64>) -> Result<Self, ImagingError> {
        let sv = m.singular_values();
        let (max, min) = (sv.max(), sv.min());
        let well_conditioned = max > 0.0 && min / max > 1e-12;
        if !well_conditioned {
            return Err(invalid(format!(
                "homography matrix is singular or nearly so (singular values {:?})",
                sv.as_slice()
            )));
        }
        let m = if m[(2, 2)].abs() > 1e-12 * max {
            m / m[(2, 2)]
        } else {
            m / m.norm()
        };
        let inverse = m
            .try_inverse()
            .ok_or_else(|| invalid("homography matrix is not invertible"))?;
        if inverse.iter().any(|v| !v.is_finite()) {
            return Err(invalid("homography matrix is not invertible"));
        }
        Ok(Self {
            forward: m,
            inverse,
        })
    }

    /// The row-major pixel → surface matrix.
    pub fn matrix(&self) -> [[f64; 3]; 3] {
        matrix_rows(&self.forward)
    }

    /// The pixel → surface matrix.
    pub fn forward(&self) -> &Matrix3<f64> {
        &self.forward
    }

    /// The surface → pixel matrix.
    pub fn inverse(&self) -> &Matrix3<f64> {
        &self.inverse
    }

    /// Surface `(x, y)` mm of pixel `(u, v)`; an error if the pixel is on the vanishing line (maps to
    /// infinity) or not finite.
    pub fn pixel_to_surface(&self, pixel: [f64; 2]) -> Result<[f64; 2], ImagingError> {
        apply_finite(&self.forward, pixel)
            .ok_or_else(|| invalid(format!("pixel {pixel:?} maps to infinity on the surface")))
    }

    /// Pixel `(u, v)` of surface point `(x, y)` mm; an error if it maps to infinity or is not finite.
    pub fn surface_to_pixel(&self, surface: [f64; 2]) -> Result<[f64; 2], ImagingError> {
        apply_finite(&self.inverse, surface).ok_or_else(|| {
            invalid(format!(
                "surface point {surface:?} maps to infinity in the image"
            ))
        })
    }

    /// Reprojection errors of `pairs` under this homography. A pair whose point maps to infinity
    /// gets an infinite error.
    pub fn reprojection_errors(&self, pairs: &[PointPair]) -> ReprojectionStats {
        let dist = |a: Option<[f64; 2]>, b: [f64; 2]| match a {
            Some(a) => (a[0] - b[0]).hypot(a[1] - b[1]),
            None => f64::INFINITY,
        };
        let per_pair_mm: Vec<f64> = pairs
            .iter()
            .map(|p| dist(apply_finite(&self.forward, p.pixel), p.surface))
            .collect();
        let per_pair_px: Vec<f64> = pairs
            .iter()
            .map(|p| dist(apply_finite(&self.inverse, p.surface), p.pixel))
            .collect();
        let rms = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                (v.iter().map(|e| e * e).sum::<f64>() / v.len() as f64).sqrt()
            }
        };
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        ReprojectionStats {
            rms_mm: rms(&per_pair_mm),
            max_mm: max(&per_pair_mm),
            rms_px: rms(&per_pair_px),
            max_px: max(&per_pair_px),
            per_pair_mm,
            per_pair_px,
        }
    }
}

/// Reprojection errors of point pairs under a homography.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReprojectionStats {
    /// Root mean square surface-side error, mm.
    pub rms_mm: f64,
    /// Largest surface-side error, mm.
    pub max_mm: f64,
    /// Root mean square image-side error, px.
    pub rms_px: f64,
    /// Largest image-side error, px.
    pub max_px: f64,
    /// Surface-side error of each pair, mm.
    pub per_pair_mm: Vec<f64>,
    /// Image-side error of each pair, px.
    pub per_pair_px: Vec<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera looking down at the plate from 250 mm, slightly tilted: plate → image.
    fn camera_like() -> Matrix3<f64> {
        Matrix3::new(700.0, 20.0, -3.0e4, -5.0, -690.0, 5.0e4, 0.01, 0.02, 250.0)
    }

    #[test]
    fn in_front_agrees_with_nalgebra_bit_for_bit_and_stops_at_the_horizon() {
        let h = camera_like();
        for p in [[0.0, 0.0], [37.5, 81.25], [-1e4, 3.0], [200.0, 100.0]] {
            let q = h * Vector3::new(p[0], p[1], 1.0);
            let got = apply_in_front(&h, p).unwrap();
            assert_eq!(got, [q.x / q.z, q.y / q.z]);
        }
        // w = 0.01 x + 0.02 y + 250 ≤ 1e-12 beyond the horizon.
        assert_eq!(apply_in_front(&h, [-25_000.0, 0.0]), None);
        assert_eq!(apply_in_front(&h, [-30_000.0, 0.0]), None);
        assert_eq!(apply_in_front(&h, [f64::NAN, 0.0]), None);
    }

    #[test]
    fn finite_accepts_negative_w_and_refuses_infinity() {
        let h = -camera_like();
        let p = [10.0, 20.0];
        assert_eq!(apply_in_front(&h, p), None, "negative w is behind a camera");
        let a = apply_finite(&h, p).unwrap();
        let b = apply_in_front(&camera_like(), p).unwrap();
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        let line = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0);
        assert_eq!(apply_finite(&line, [-1.0, 5.0]), None);
        assert_eq!(apply_finite(&line, [f64::NAN, 5.0]), None);
        assert!(apply_finite(&line, [1.0, 5.0]).is_some());
    }

    #[test]
    fn homography_round_trips_and_refuses_bad_matrices() {
        let h = Homography::from_nalgebra(camera_like().try_inverse().unwrap()).unwrap();
        assert_eq!(h.forward()[(2, 2)], 1.0);
        let pairs: Vec<PointPair> = [[0.0, 0.0], [200.0, 0.0], [200.0, 100.0], [0.0, 100.0]]
            .iter()
            .map(|&s| PointPair::new(h.surface_to_pixel(s).unwrap(), s))
            .collect();
        let stats = h.reprojection_errors(&pairs);
        assert!(stats.max_mm < 1e-9 && stats.max_px < 1e-9, "{stats:?}");
        assert_eq!(Homography::from_matrix(h.matrix()).unwrap(), h);
        assert!(Homography::from_matrix([[0.0; 3]; 3]).is_err());
        let err = Homography::from_matrix([[f64::NAN, 0.0, 0.0], [0.0; 3], [0.0; 3]]).unwrap_err();
        assert!(err.to_string().contains("non-finite"), "{err}");
    }
}
