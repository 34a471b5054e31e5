//! The lens: OpenCV's pinhole with Brown–Conrady distortion.
//!
//! A point `(X, Y, Z)` in the camera frame (x right, y down, z forward) has normalised
//! coordinates `x = X/Z`, `y = Y/Z`, `r² = x² + y²`, and is seen at
//!
//! ```text
//! radial = 1 + k1 r² + k2 r⁴ + k3 r⁶
//! x_d = x radial + 2 p1 x y + p2 (r² + 2 x²)
//! y_d = y radial + p1 (r² + 2 y²) + 2 p2 x y
//! u = fx x_d + cx,   v = fy y_d + cy
//! ```

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Focal lengths and principal point, pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Intrinsics {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point, x, pixels.
    pub cx: f64,
    /// Principal point, y, pixels.
    pub cy: f64,
}

/// Distortion coefficients in OpenCV's order.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Distortion {
    /// Radial, r².
    pub k1: f64,
    /// Radial, r⁴.
    pub k2: f64,
    /// Tangential.
    pub p1: f64,
    /// Tangential.
    pub p2: f64,
    /// Radial, r⁶.
    pub k3: f64,
}

impl Distortion {
    /// In OpenCV's order: `[k1, k2, p1, p2, k3]`.
    pub fn to_array(self) -> [f64; 5] {
        [self.k1, self.k2, self.p1, self.p2, self.k3]
    }

    /// From OpenCV's order.
    pub fn from_array(d: [f64; 5]) -> Self {
        Distortion {
            k1: d[0],
            k2: d[1],
            p1: d[2],
            p2: d[3],
            k3: d[4],
        }
    }

    /// Distorts normalised coordinates.
    pub fn apply(&self, p: Vector2<f64>) -> Vector2<f64> {
        let (x, y) = (p.x, p.y);
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        Vector2::new(
            x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// The Jacobian of [`apply`](Self::apply) at `p`.
    fn jacobian(&self, p: Vector2<f64>) -> Matrix2<f64> {
        let (x, y) = (p.x, p.y);
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (self.k1 + r2 * (self.k2 + r2 * self.k3));
        let d_radial = self.k1 + r2 * (2.0 * self.k2 + 3.0 * self.k3 * r2);
        let cross = 2.0 * x * y * d_radial + 2.0 * self.p1 * x + 2.0 * self.p2 * y;
        Matrix2::new(
            radial + 2.0 * x * x * d_radial + 2.0 * self.p1 * y + 6.0 * self.p2 * x,
            cross,
            cross,
            radial + 2.0 * y * y * d_radial + 6.0 * self.p1 * y + 2.0 * self.p2 * x,
        )
    }

    /// Undoes [`apply`](Self::apply) by Newton's method: the normalised point that distorts to
    /// `d`, or `None` where the model folds over (no unique answer near `d`: far outside the
    /// image a strong barrel distortion turns back on itself).
    pub fn remove(&self, d: Vector2<f64>) -> Option<Vector2<f64>> {
        let mut p = d;
        for _ in 0..50 {
            let residual = self.apply(p) - d;
            if residual.norm() < 1e-13 {
                return Some(p);
            }
            let step = self.jacobian(p).try_inverse()? * residual;
            p -= step;
            if !(p.x.is_finite() && p.y.is_finite()) {
                return None;
            }
        }
        ((self.apply(p) - d).norm() < 1e-10).then_some(p)
    }
}

/// Intrinsics and distortion together.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Lens {
    /// Focal lengths and principal point.
    pub intrinsics: Intrinsics,
    /// Distortion.
    pub distortion: Distortion,
}

impl Lens {
    /// The pixel where the camera-frame point `p` is seen; `None` behind the camera.
    pub fn project(&self, p: Vector3<f64>) -> Option<[f64; 2]> {
        if p.z <= 0.0 {
            return None;
        }
        let d = self.distortion.apply(Vector2::new(p.x / p.z, p.y / p.z));
        let k = &self.intrinsics;
        Some([k.fx * d.x + k.cx, k.fy * d.y + k.cy])
    }

    /// The ray through pixel `uv`, as normalised coordinates `(x, y)` (the direction
    /// `(x, y, 1)` in the camera frame); `None` where the distortion cannot be undone.
    pub fn unproject(&self, uv: [f64; 2]) -> Option<Vector2<f64>> {
        let k = &self.intrinsics;
        let d = Vector2::new((uv[0] - k.cx) / k.fx, (uv[1] - k.cy) / k.fy);
        self.distortion.remove(d)
    }

    /// Where pixel `uv` would be seen by the same pinhole without distortion.
    pub fn undistort_pixel(&self, uv: [f64; 2]) -> Option<[f64; 2]> {
        let p = self.unproject(uv)?;
        let k = &self.intrinsics;
        Some([k.fx * p.x + k.cx, k.fy * p.y + k.cy])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn webcam(k1: f64) -> Lens {
        Lens {
            intrinsics: Intrinsics {
                fx: 900.0,
                fy: 905.0,
                cx: 641.0,
                cy: 359.0,
            },
            distortion: Distortion {
                k1,
                k2: 0.3 * k1.abs(),
                p1: 0.001,
                p2: -0.0007,
                k3: 0.0,
            },
        }
    }

    #[test]
    fn undistortion_inverts_distortion_over_the_whole_image() {
        for k1 in [-0.35, -0.2, 0.0, 0.1] {
            let lens = webcam(k1);
            for row in 0..=18 {
                for col in 0..=32 {
                    let uv = [f64::from(col) * 40.0, f64::from(row) * 40.0];
                    let p = lens.unproject(uv).expect("undistortable inside the image");
                    let back = lens.project(Vector3::new(p.x, p.y, 1.0)).expect("in front");
                    let err = (back[0] - uv[0]).hypot(back[1] - uv[1]);
                    assert!(err < 1e-8, "k1 {k1}: {uv:?} came back {err} px off");
                }
            }
        }
    }

    #[test]
    fn the_jacobian_is_the_derivative() {
        let d = webcam(-0.3).distortion;
        let d = Distortion { k3: 0.05, ..d };
        let p = Vector2::new(0.4, -0.3);
        let j = d.jacobian(p);
        let h = 1e-7;
        for i in 0..2 {
            let mut e = Vector2::zeros();
            e[i] = h;
            let numeric = (d.apply(p + e) - d.apply(p - e)) / (2.0 * h);
            for r in 0..2 {
                assert!((numeric[r] - j[(r, i)]).abs() < 1e-6, "{numeric} vs {j}");
            }
        }
    }

    #[test]
    fn opencvs_order_round_trips() {
        let d = Distortion::from_array([0.1, 0.2, 0.3, 0.4, 0.5]);
        assert_eq!(d.p1, 0.3);
        assert_eq!(d.to_array(), [0.1, 0.2, 0.3, 0.4, 0.5]);
    }
}
