//! Rigid poses: a rotation (stored as its rotation vector) and a translation, mapping a
//! target's (or plate's) frame into the camera's.

use nalgebra::{Rotation3, Vector3};
use serde::{Deserialize, Serialize};

/// `p_camera = R p_target + t`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Rotation vector (axis × angle, radians), as OpenCV's `rvec`.
    pub rotation: [f64; 3],
    /// Translation, the target's origin in the camera frame, mm (OpenCV's `tvec`).
    pub translation: [f64; 3],
}

impl Pose {
    /// From a rotation matrix and a translation.
    pub fn new(r: &Rotation3<f64>, t: Vector3<f64>) -> Self {
        let v = r.scaled_axis();
        Pose {
            rotation: [v.x, v.y, v.z],
            translation: [t.x, t.y, t.z],
        }
    }

    /// The rotation.
    pub fn rotation(&self) -> Rotation3<f64> {
        Rotation3::new(Vector3::from(self.rotation))
    }

    /// The translation.
    pub fn translation(&self) -> Vector3<f64> {
        Vector3::from(self.translation)
    }

    /// A target-frame point in the camera frame.
    pub fn apply(&self, p: Vector3<f64>) -> Vector3<f64> {
        self.rotation() * p + self.translation()
    }

    /// Angle between the target's normal (its z axis) and the camera's optical axis, degrees:
    /// 0 face-on, 90 edge-on.
    pub fn tilt_deg(&self) -> f64 {
        let normal = self.rotation() * Vector3::z();
        normal.z.abs().clamp(0.0, 1.0).acos().to_degrees()
    }

    /// The camera's optical centre in the target's frame.
    pub fn camera_centre(&self) -> Vector3<f64> {
        -(self.rotation().inverse() * self.translation())
    }
}
