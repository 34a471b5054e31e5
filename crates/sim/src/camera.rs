//! The pinhole camera of a scene: intrinsics `K` from the focal lengths and principal point, the
//! pose from the optical centre, the point looked at on the plate and a roll, and the exact
//! homography between the plate's top face (z = 0, mm) and the image (pixels), and optionally
//! lens distortion (OpenCV's model, `crackbot_calib::lens`): the image is then what the pinhole
//! would see, distorted, and the homography is the pinhole's (exact only without distortion).
//!
//! Conventions:
//! * Continuous pixel coordinates: the top-left corner of the image is `(0, 0)`, so pixel
//!   `(col, row)` covers `[col, col + 1) × [row, row + 1)` and its centre is
//!   `(col + 0.5, row + 0.5)` (the default principal point, `(w/2, h/2)`, is the image centre).
//! * Camera frame: x right, y down in the image, z forward along the optical axis. With
//!   `roll_deg = 0` the camera's x axis is `f × ŷ` normalised (`f` the viewing direction, `ŷ`
//!   the plate's +y), which for a camera looking straight down is plate +x, and its y axis is
//!   `f × x`, plate −y straight down. A positive roll turns the camera's x and y axes by that
//!   angle about the optical axis (from x towards y), so the scene appears turned the other way.

use crackbot_calib::{Distortion, Intrinsics, Lens};
pub use crackbot_imaging::homography::apply_in_front as apply_homography;
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::{list, SimError};

/// A pinhole camera above the plate.
///
/// The camera frame is the usual one (x right, y down in the image, z forward). Its pose is
/// given as the position of the optical centre in the plate's frame (mm, z up, plate top at 0)
/// and the point it looks at on the plate, plus a roll about the optical axis. With `look_at`
/// straight below `position_mm` and `roll_deg = 0`, image x runs along plate +x and image y
/// along plate −y (the plate is seen from above as drawn on paper).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Image size in pixels `[width, height]`.
    pub resolution: [u32; 2],
    /// Focal lengths in pixels `[fx, fy]`.
    pub focal_px: [f64; 2],
    /// Principal point in pixels `[cx, cy]` (default: image centre).
    #[serde(default)]
    pub principal_px: Option<[f64; 2]>,
    /// Optical centre in the plate's frame, mm `[x, y, z]`.
    pub position_mm: [f64; 3],
    /// Point on the plate (z = 0) the optical axis passes through, mm `[x, y]`.
    pub look_at_mm: [f64; 2],
    /// Rotation about the optical axis, degrees.
    #[serde(default)]
    pub roll_deg: f64,
    /// Standard deviation of the sensor's noise, in 8-bit grey levels.
    #[serde(default = "default_image_noise")]
    pub noise_sigma: f64,
    /// Relative spread of the lighting between frames (0: identical lighting).
    #[serde(default = "default_lighting_variation")]
    pub lighting_variation: f64,
    /// Lens distortion in OpenCV's order `[k1, k2, p1, p2, k3]` (default: none, a pinhole).
    #[serde(default)]
    pub distortion: [f64; 5],
}

fn default_image_noise() -> f64 {
    2.0
}
fn default_lighting_variation() -> f64 {
    0.15
}

/// The distorting lens of `spec`, or `None` for a pinhole; fails on non-finite coefficients or
/// a distortion that folds the image over itself (not one-to-one over the frame).
fn lens_of(spec: &CameraSpec, f: [f64; 2], c: [f64; 2]) -> Result<Option<Lens>, SimError> {
    let d = spec.distortion;
    if !d.iter().all(|v| v.is_finite()) {
        return Err(SimError::setting("camera.distortion", list(&d), "finite"));
    }
    if d.iter().all(|&v| v == 0.0) {
        return Ok(None);
    }
    let lens = Lens {
        intrinsics: Intrinsics {
            fx: f[0],
            fy: f[1],
            cx: c[0],
            cy: c[1],
        },
        distortion: Distortion::from_array(d),
    };
    // Every pixel of the frame must come from one ray: at the corners and edge midpoints the
    // distortion must be undone (Newton converges) and still spread outwards (inside the fold).
    let [w, h] = spec.resolution.map(f64::from);
    for uv in [
        [0.0, 0.0],
        [w, 0.0],
        [0.0, h],
        [w, h],
        [w / 2.0, 0.0],
        [0.0, h / 2.0],
    ] {
        let ok = lens.unproject(uv).is_some_and(|n| {
            let out = lens.distortion.apply(n * 1.001).norm();
            let here = lens.distortion.apply(n).norm();
            n.norm() < 1e-12 || out > here
        });
        if !ok {
            return Err(SimError::setting(
                "camera.distortion",
                list(&d),
                "a distortion the frame's corners can be undistorted through (it folds over)",
            ));
        }
    }
    Ok(Some(lens))
}

/// A calibrated pinhole camera looking at the plate.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    width: u32,
    height: u32,
    /// Intrinsics.
    k: Matrix3<f64>,
    /// Rows: the camera's x, y and z (forward) axes in the plate's frame.
    r: Matrix3<f64>,
    /// Optical centre in the plate's frame, mm.
    centre: Vector3<f64>,
    /// Plate (z = 0, mm) → pixels.
    h: Matrix3<f64>,
    /// Pixels → plate (z = 0, mm).
    h_inv: Matrix3<f64>,
    /// The lens, when it distorts (`None`: an exact pinhole).
    lens: Option<Lens>,
}

impl Camera {
    /// Builds the camera of `spec`. Fails (naming the field) on non-finite numbers, a zero
    /// resolution, non-positive focal lengths, a camera on the plate's plane, or a viewing
    /// direction along the plate's y axis (where roll 0 is undefined).
    pub fn from_spec(spec: &CameraSpec) -> Result<Camera, SimError> {
        let [width, height] = spec.resolution;
        if width == 0 || height == 0 {
            return Err(SimError::setting(
                "camera.resolution",
                list(&spec.resolution),
                "> 0 in width and height",
            ));
        }
        let [fx, fy] = spec.focal_px;
        if !(fx.is_finite() && fx > 0.0 && fy.is_finite() && fy > 0.0) {
            return Err(SimError::setting(
                "camera.focal_px",
                list(&spec.focal_px),
                "> 0 in x and y",
            ));
        }
        let [cx, cy] = spec
            .principal_px
            .unwrap_or([f64::from(width) / 2.0, f64::from(height) / 2.0]);
        if !(cx.is_finite() && cy.is_finite()) {
            return Err(SimError::setting(
                "camera.principal_px",
                list(&[cx, cy]),
                "finite",
            ));
        }
        if !spec.position_mm.iter().all(|v| v.is_finite()) {
            return Err(SimError::setting(
                "camera.position_mm",
                list(&spec.position_mm),
                "finite",
            ));
        }
        if !spec.look_at_mm.iter().all(|v| v.is_finite()) {
            return Err(SimError::setting(
                "camera.look_at_mm",
                list(&spec.look_at_mm),
                "finite",
            ));
        }
        if !spec.roll_deg.is_finite() {
            return Err(SimError::setting(
                "camera.roll_deg",
                spec.roll_deg,
                "finite",
            ));
        }
        let lens = lens_of(spec, [fx, fy], [cx, cy])?;
        let centre = Vector3::from(spec.position_mm);
        if centre.z.abs() < 1e-9 {
            return Err(SimError::setting(
                "camera.position_mm",
                list(&spec.position_mm),
                "off the plate's plane (z ≠ 0)",
            ));
        }
        let target = Vector3::new(spec.look_at_mm[0], spec.look_at_mm[1], 0.0);
        let forward = (target - centre).normalize();
        let x0 = forward.cross(&Vector3::y());
        if x0.norm() < 1e-6 {
            return Err(SimError::setting(
                "camera.position_mm",
                list(&spec.position_mm),
                format!(
                    "off the line along the plate's y axis through camera.look_at_mm {} (roll 0 \
                     is undefined looking along it)",
                    list(&spec.look_at_mm)
                ),
            ));
        }
        let x0 = x0.normalize();
        let y0 = forward.cross(&x0);
        let (s, c) = spec.roll_deg.to_radians().sin_cos();
        let x = x0 * c + y0 * s;
        let y = y0 * c - x0 * s;
        let r = Matrix3::from_rows(&[x.transpose(), y.transpose(), forward.transpose()]);
        let k = Matrix3::new(fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0);
        let t = -(r * centre);
        let h = k * Matrix3::from_columns(&[r.column(0).into_owned(), r.column(1).into_owned(), t]);
        let h_inv = h.try_inverse().ok_or_else(|| SimError::Homography {
            message: "the camera's plate-to-image homography is singular".to_string(),
        })?;
        Ok(Camera {
            width,
            height,
            k,
            r,
            centre,
            h,
            h_inv,
            lens,
        })
    }

    /// The lens model of this camera (intrinsics and distortion, zero for a pinhole).
    pub fn lens(&self) -> Lens {
        self.lens.unwrap_or(Lens {
            intrinsics: Intrinsics {
                fx: self.k[(0, 0)],
                fy: self.k[(1, 1)],
                cx: self.k[(0, 2)],
                cy: self.k[(1, 2)],
            },
            distortion: Distortion::default(),
        })
    }

    /// Where the pinhole without distortion would see what this camera sees at `uv` (`uv`
    /// itself for a pinhole; `None` where the distortion cannot be undone).
    pub fn undistort(&self, uv: [f64; 2]) -> Option<[f64; 2]> {
        match &self.lens {
            None => Some(uv),
            Some(lens) => lens.undistort_pixel(uv),
        }
    }

    /// The plate point (z = 0, mm) seen at pixel `uv`, through the lens; `None` at or above the
    /// horizon.
    pub fn plate_point(&self, uv: [f64; 2]) -> Option<[f64; 2]> {
        apply_homography(&self.h_inv, self.undistort(uv)?)
    }

    /// Image width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The intrinsic matrix `K`.
    pub fn intrinsics(&self) -> Matrix3<f64> {
        self.k
    }

    /// The rotation from the plate's frame to the camera's frame (rows: the camera's axes).
    pub fn rotation(&self) -> Matrix3<f64> {
        self.r
    }

    /// The optical centre in the plate's frame, mm.
    pub fn centre_mm(&self) -> [f64; 3] {
        [self.centre.x, self.centre.y, self.centre.z]
    }

    /// The viewing direction (unit vector of the optical axis) in the plate's frame.
    pub fn forward(&self) -> [f64; 3] {
        [self.r[(2, 0)], self.r[(2, 1)], self.r[(2, 2)]]
    }

    /// Pixel coordinates of the point `p_mm` (plate frame, mm), or `None` when it is not in
    /// front of the camera. The result may lie outside the image.
    pub fn project(&self, p_mm: [f64; 3]) -> Option<[f64; 2]> {
        let pc = self.r * (Vector3::from(p_mm) - self.centre);
        if pc.z.is_nan() || pc.z <= 1e-9 {
            return None;
        }
        match &self.lens {
            Some(lens) => lens.project(pc),
            None => {
                let q = self.k * pc;
                Some([q.x / q.z, q.y / q.z])
            }
        }
    }

    /// The ray through the pixel coordinates `uv`: unit direction in the plate's frame (from
    /// the optical centre).
    pub fn ray(&self, uv: [f64; 2]) -> [f64; 3] {
        let uv = self.undistort(uv).unwrap_or(uv);
        let fx = self.k[(0, 0)];
        let fy = self.k[(1, 1)];
        let dc = Vector3::new(
            (uv[0] - self.k[(0, 2)]) / fx,
            (uv[1] - self.k[(1, 2)]) / fy,
            1.0,
        );
        let d = (self.r.transpose() * dc).normalize();
        [d.x, d.y, d.z]
    }

    /// Where the ray through `uv` meets the horizontal plane `z = z_mm`, `[x, y]` mm, or `None`
    /// when it does not meet it in front of the camera.
    pub fn pixel_to_plane(&self, uv: [f64; 2], z_mm: f64) -> Option<[f64; 2]> {
        let d = self.ray(uv);
        if d[2].abs() < 1e-12 {
            return None;
        }
        let t = (z_mm - self.centre.z) / d[2];
        if t.is_nan() || t <= 0.0 {
            return None;
        }
        Some([self.centre.x + t * d[0], self.centre.y + t * d[1]])
    }

    /// The pinhole's homography from plate coordinates (mm, on the plate's top face z = 0) to
    /// pixel coordinates: `[u, v, 1]ᵀ ∝ H [x, y, 1]ᵀ`; exact when the lens does not distort,
    /// else the map to the undistorted image.
    pub fn plate_to_image(&self) -> Matrix3<f64> {
        self.h
    }

    /// The inverse of [`Camera::plate_to_image`]: pixels to plate mm (z = 0).
    pub fn image_to_plate(&self) -> Matrix3<f64> {
        self.h_inv
    }

    /// Whether the pixel coordinates lie inside the image.
    pub fn in_image(&self, uv: [f64; 2]) -> bool {
        uv[0] >= 0.0
            && uv[1] >= 0.0
            && uv[0] < f64::from(self.width)
            && uv[1] < f64::from(self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(position: [f64; 3], look_at: [f64; 2], roll: f64) -> CameraSpec {
        CameraSpec {
            resolution: [640, 480],
            focal_px: [700.0, 690.0],
            principal_px: None,
            position_mm: position,
            look_at_mm: look_at,
            roll_deg: roll,
            noise_sigma: 0.0,
            lighting_variation: 0.0,
            distortion: [0.0; 5],
        }
    }

    #[test]
    fn projection_agrees_with_the_homography_on_the_plate() {
        for s in [
            spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0),
            spec([40.0, -80.0, 200.0], [100.0, 50.0], 17.0),
            spec([260.0, 120.0, 150.0], [90.0, 40.0], -95.0),
        ] {
            let cam = Camera::from_spec(&s).unwrap();
            let h = cam.plate_to_image();
            let hi = cam.image_to_plate();
            for p in [[0.0, 0.0], [200.0, 0.0], [37.5, 81.25], [100.0, 50.0]] {
                let a = cam.project([p[0], p[1], 0.0]).unwrap();
                let b = apply_homography(&h, p).unwrap();
                assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
                let back = apply_homography(&hi, b).unwrap();
                assert!((back[0] - p[0]).abs() < 1e-9 && (back[1] - p[1]).abs() < 1e-9);
                let via_ray = cam.pixel_to_plane(b, 0.0).unwrap();
                assert!((via_ray[0] - p[0]).abs() < 1e-9 && (via_ray[1] - p[1]).abs() < 1e-9);
            }
            // The look-at point lands on the principal point.
            let c = cam
                .project([s.look_at_mm[0], s.look_at_mm[1], 0.0])
                .unwrap();
            assert!((c[0] - 320.0).abs() < 1e-9 && (c[1] - 240.0).abs() < 1e-9);
        }
    }

    #[test]
    fn straight_down_maps_plate_x_to_image_x_and_plate_y_to_image_minus_y() {
        let cam = Camera::from_spec(&spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0)).unwrap();
        let o = cam.project([100.0, 50.0, 0.0]).unwrap();
        let px = cam.project([110.0, 50.0, 0.0]).unwrap();
        let py = cam.project([100.0, 60.0, 0.0]).unwrap();
        assert!((px[0] - o[0] - 700.0 * 10.0 / 250.0).abs() < 1e-9);
        assert!((px[1] - o[1]).abs() < 1e-9);
        assert!((py[1] - o[1] + 690.0 * 10.0 / 250.0).abs() < 1e-9);
        assert!((py[0] - o[0]).abs() < 1e-9);
        // Roll 90°: plate +x now runs along image −y.
        let cam = Camera::from_spec(&spec([100.0, 50.0, 250.0], [100.0, 50.0], 90.0)).unwrap();
        let px = cam.project([110.0, 50.0, 0.0]).unwrap();
        assert!(px[1] < 240.0 - 20.0 && (px[0] - 320.0).abs() < 1e-9);
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        let cam = Camera::from_spec(&spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0)).unwrap();
        assert!(cam.project([100.0, 50.0, 300.0]).is_none());
        assert!(cam.project([100.0, 50.0, 250.0]).is_none());
    }

    #[test]
    fn bad_specs_are_refused() {
        let mut s = spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0);
        s.focal_px = [0.0, 700.0];
        assert!(Camera::from_spec(&s).is_err());
        let mut s = spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0);
        s.resolution = [0, 480];
        assert!(Camera::from_spec(&s).is_err());
        let s = spec([100.0, 50.0, f64::NAN], [100.0, 50.0], 0.0);
        assert!(Camera::from_spec(&s).is_err());
        let s = spec([100.0, 50.0, 0.0], [100.0, 50.0], 0.0);
        assert!(Camera::from_spec(&s).is_err());
    }

    #[test]
    fn a_distorting_lens_projects_and_unprojects_through_the_same_model() {
        let mut s = spec([100.0, 50.0, 250.0], [100.0, 50.0], 10.0);
        s.distortion = [-0.3, 0.09, 0.001, -0.0008, 0.0];
        let cam = Camera::from_spec(&s).unwrap();
        let pinhole = Camera::from_spec(&CameraSpec {
            distortion: [0.0; 5],
            ..s.clone()
        })
        .unwrap();
        for p in [[0.0, 0.0], [200.0, 100.0], [10.0, 90.0], [100.0, 50.0]] {
            let uv = cam.project([p[0], p[1], 0.0]).unwrap();
            let back = cam.plate_point(uv).unwrap();
            assert!((back[0] - p[0]).abs() < 1e-6 && (back[1] - p[1]).abs() < 1e-6);
            let via_ray = cam.pixel_to_plane(uv, 0.0).unwrap();
            assert!((via_ray[0] - p[0]).abs() < 1e-6 && (via_ray[1] - p[1]).abs() < 1e-6);
            // Barrel distortion pulls points towards the centre.
            let ideal = pinhole.project([p[0], p[1], 0.0]).unwrap();
            let r = |q: [f64; 2]| (q[0] - 320.0).hypot(q[1] - 240.0);
            assert!(r(uv) <= r(ideal) + 1e-9);
        }
    }

    #[test]
    fn a_distortion_that_folds_the_frame_over_is_refused() {
        let mut s = spec([100.0, 50.0, 250.0], [100.0, 50.0], 0.0);
        s.distortion = [-1.5, 0.0, 0.0, 0.0, 0.0];
        let err = Camera::from_spec(&s).unwrap_err().to_string();
        assert!(err.contains("camera.distortion"), "{err}");
        s.distortion = [f64::NAN, 0.0, 0.0, 0.0, 0.0];
        assert!(Camera::from_spec(&s).is_err());
    }
}
