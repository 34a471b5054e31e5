//! The surface frame in the arm's base frame: where the plate lies for the arm.
//!
//! The link speaks millimetres in the surface frame (x, y along the plate, z away from it, 0 on
//! it); a ROS 2 arm speaks metres in its base frame. [`SurfaceFrame`] is the rigid transform
//! between them, `p_base = R · p_surface + origin`, read from the site file's `[surface]` table
//! (written by `crackbot-controller register`):
//!
//! ```toml
//! [surface]
//! origin_m = [0.45, -0.10, 0.02]          # the surface frame's origin in the base frame, m
//! rotation_xyzw = [0.0, 0.0, 0.0, 1.0]    # the surface frame's axes in the base frame (unit quaternion)
//! tool_xyzw = [1.0, 0.0, 0.0, 0.0]        # the tool's orientation in the surface frame (default: pointing down, −z)
//! ```

use serde::{Deserialize, Serialize};

/// A unit quaternion `[x, y, z, w]`.
pub type Quat = [f64; 4];

/// The surface frame's pose in the arm's base frame, and the tool's orientation on it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceFrame {
    /// The surface frame's origin in the base frame, m.
    pub origin_m: [f64; 3],
    /// The surface frame's axes in the base frame, a unit quaternion `[x, y, z, w]`.
    pub rotation_xyzw: Quat,
    /// The tool's orientation in the surface frame (its z axis along the finger, pointing into
    /// the plate): default a half turn about x, the tool looking down.
    #[serde(default = "tool_down")]
    pub tool_xyzw: Quat,
}

fn tool_down() -> Quat {
    [1.0, 0.0, 0.0, 0.0]
}

/// A surface frame that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// A value is NaN or infinite.
    #[error("surface.{field} holds a value that is not finite")]
    NotFinite {
        /// Which field.
        field: &'static str,
    },
    /// A quaternion is far from unit length (a typo, not rounding).
    #[error("surface.{field} has length {norm:.4}, not 1 (a unit quaternion [x, y, z, w])")]
    NotUnit {
        /// Which field.
        field: &'static str,
        /// Its length.
        norm: f64,
    },
}

impl Default for SurfaceFrame {
    /// The surface frame is the base frame (the simulated arm's case).
    fn default() -> Self {
        SurfaceFrame {
            origin_m: [0.0; 3],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
            tool_xyzw: tool_down(),
        }
    }
}

/// Checks a quaternion and scales it to unit length.
fn unit(field: &'static str, q: Quat) -> Result<Quat, FrameError> {
    if !q.iter().all(|v| v.is_finite()) {
        return Err(FrameError::NotFinite { field });
    }
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-3 {
        return Err(FrameError::NotUnit { field, norm });
    }
    Ok(q.map(|v| v / norm))
}

/// The Hamilton product `a · b`.
pub fn quat_mul(a: Quat, b: Quat) -> Quat {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// `v` rotated by the unit quaternion `q`.
pub fn rotate(q: Quat, v: [f64; 3]) -> [f64; 3] {
    let p = quat_mul(quat_mul(q, [v[0], v[1], v[2], 0.0]), conjugate(q));
    [p[0], p[1], p[2]]
}

/// The inverse rotation of a unit quaternion.
pub fn conjugate(q: Quat) -> Quat {
    [-q[0], -q[1], -q[2], q[3]]
}

impl SurfaceFrame {
    /// Checks the values once: finite, unit quaternions (normalised).
    pub fn checked(self) -> Result<SurfaceFrame, FrameError> {
        if !self.origin_m.iter().all(|v| v.is_finite()) {
            return Err(FrameError::NotFinite { field: "origin_m" });
        }
        Ok(SurfaceFrame {
            origin_m: self.origin_m,
            rotation_xyzw: unit("rotation_xyzw", self.rotation_xyzw)?,
            tool_xyzw: unit("tool_xyzw", self.tool_xyzw)?,
        })
    }

    /// A point of the surface frame (mm) in the base frame (m).
    pub fn to_base(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let r = rotate(self.rotation_xyzw, p_mm.map(|v| v * 1e-3));
        [
            r[0] + self.origin_m[0],
            r[1] + self.origin_m[1],
            r[2] + self.origin_m[2],
        ]
    }

    /// A point of the base frame (m) in the surface frame (mm).
    pub fn to_surface(&self, p_m: [f64; 3]) -> [f64; 3] {
        let d = [
            p_m[0] - self.origin_m[0],
            p_m[1] - self.origin_m[1],
            p_m[2] - self.origin_m[2],
        ];
        rotate(conjugate(self.rotation_xyzw), d).map(|v| v * 1e3)
    }

    /// The tool's orientation in the base frame.
    pub fn tool_in_base(&self) -> Quat {
        quat_mul(self.rotation_xyzw, self.tool_xyzw)
    }

    /// The surface's normal (its z axis) in the base frame.
    pub fn normal(&self) -> [f64; 3] {
        rotate(self.rotation_xyzw, [0.0, 0.0, 1.0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted() -> SurfaceFrame {
        // 30° about an oblique axis, offset.
        let axis = [0.3f64, -0.5, 0.81];
        let n = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
        let h = 30f64.to_radians() / 2.0;
        SurfaceFrame {
            origin_m: [0.4, -0.1, 0.05],
            rotation_xyzw: [
                axis[0] / n * h.sin(),
                axis[1] / n * h.sin(),
                axis[2] / n * h.sin(),
                h.cos(),
            ],
            tool_xyzw: tool_down(),
        }
        .checked()
        .expect("unit")
    }

    #[test]
    fn a_point_goes_to_the_base_frame_and_back() {
        let f = tilted();
        for p in [[0.0, 0.0, 0.0], [200.0, 100.0, -1.0], [13.5, 87.2, 50.0]] {
            let back = f.to_surface(f.to_base(p));
            for k in 0..3 {
                assert!((back[k] - p[k]).abs() < 1e-9, "{p:?} → {back:?}");
            }
        }
        // Distances are kept (a rigid transform) and the origin is where the file says.
        let (a, b) = (f.to_base([0.0; 3]), f.to_base([100.0, 0.0, 0.0]));
        assert!((a[0] - 0.4).abs() < 1e-12 && (a[2] - 0.05).abs() < 1e-12);
        let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
        assert!((d - 0.1).abs() < 1e-12, "{d}");
    }

    #[test]
    fn the_tool_looks_down_the_surfaces_normal() {
        let f = tilted();
        let tool_z = rotate(f.tool_in_base(), [0.0, 0.0, 1.0]);
        let n = f.normal();
        for k in 0..3 {
            assert!((tool_z[k] + n[k]).abs() < 1e-12, "{tool_z:?} vs {n:?}");
        }
    }

    #[test]
    fn a_broken_quaternion_is_named() {
        let mut f = SurfaceFrame {
            rotation_xyzw: [0.0, 0.0, 0.0, 2.0],
            ..SurfaceFrame::default()
        };
        let e = f.checked().unwrap_err();
        assert!(
            e.to_string().contains("rotation_xyzw has length 2.0000"),
            "{e}"
        );
        f.rotation_xyzw = [f64::NAN, 0.0, 0.0, 1.0];
        assert!(matches!(f.checked(), Err(FrameError::NotFinite { .. })));
        f = SurfaceFrame::default();
        f.origin_m[1] = f64::INFINITY;
        assert!(f.checked().unwrap_err().to_string().contains("origin_m"));
    }
}
