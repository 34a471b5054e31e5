//! The whole calibration from views of a flat target, and what it gives: pixel → plane.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::lens::{Distortion, Lens};
use crate::pose::Pose;
use crate::refine::{self, Points, ALL_BUT_K3, POSES_ONLY};
use crate::{homography, zhang, CalibError};

/// The target's points found in one image: target millimetres (z = 0) and their pixels, matched
/// by index.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Target points, mm.
    pub target: Vec<[f64; 2]>,
    /// Their pixels.
    pub image: Vec<[f64; 2]>,
}

/// Choices of a calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Fit k3 too (wide-angle lenses); off, it stays 0, as is safer for webcams.
    pub estimate_k3: bool,
    /// Views seen more than this far from face-on are refused, degrees.
    pub max_tilt_deg: f64,
    /// Fewest views.
    pub min_views: usize,
    /// Fewest points in a view.
    pub min_points: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            estimate_k3: false,
            max_tilt_deg: 75.0,
            min_views: 3,
            min_points: 8,
        }
    }
}

/// A calibrated camera: its lens, each view's pose and the fit's errors.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The lens.
    pub lens: Lens,
    /// The pose of the target in each view (target → camera).
    pub poses: Vec<Pose>,
    /// RMS reprojection error over all points, pixels.
    pub rms_px: f64,
    /// RMS per view, pixels.
    pub view_rms_px: Vec<f64>,
}

/// Checks a view: enough points, matched, finite.
fn check_view(k: usize, view: &View, options: &Options) -> Result<(), CalibError> {
    let got = view.target.len().min(view.image.len());
    if view.target.len() != view.image.len() || got < options.min_points {
        return Err(CalibError::TooFewPoints {
            view: k,
            got,
            need: options.min_points,
        });
    }
    let finite = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
    if let Some(i) = (0..got).find(|&i| !(finite(&view.target[i]) && finite(&view.image[i]))) {
        return Err(CalibError::NotFinite { view: k, point: i });
    }
    Ok(())
}

fn points(views: &[View]) -> Vec<Points<'_>> {
    views
        .iter()
        .map(|v| Points {
            target: &v.target,
            image: &v.image,
        })
        .collect()
}

/// Calibrates the lens from `views` of a flat target taken by a camera of `image_size` pixels.
///
/// Zhang's closed form for the intrinsics and poses, then Levenberg–Marquardt over everything
/// with the distortion (k1, k2, p1, p2, and k3 when asked). Refuses fewer than
/// `options.min_views` views or `options.min_points` points in one, coordinates that are not
/// finite, views whose points are on one line, views nearly edge-on, and views all alike (all
/// face-on, or all tilted the same way: the focal length is then not determined).
pub fn calibrate(
    views: &[View],
    image_size: [u32; 2],
    options: &Options,
) -> Result<Calibration, CalibError> {
    if views.len() < options.min_views {
        return Err(CalibError::TooFewViews {
            got: views.len(),
            need: options.min_views,
        });
    }
    let mut homographies = Vec::with_capacity(views.len());
    for (k, view) in views.iter().enumerate() {
        check_view(k, view, options)?;
        homographies.push(homography::fit(&view.target, &view.image).ok_or_else(|| {
            CalibError::Degenerate {
                view: k,
                reason: "its points lie on one line or repeat".into(),
            }
        })?);
    }
    let [w, h] = image_size.map(f64::from);
    let intrinsics = zhang::intrinsics(&homographies, [w / 2.0, h / 2.0], 2.0 / (w + h))
        .map_err(|reason| CalibError::Unconstrained { reason })?;
    let mut poses = Vec::with_capacity(views.len());
    for (k, h) in homographies.iter().enumerate() {
        let pose = zhang::pose(h, &intrinsics).ok_or_else(|| CalibError::Degenerate {
            view: k,
            reason: "no pose fits its homography".into(),
        })?;
        check_tilt(k, &pose, options)?;
        poses.push(pose);
    }
    let start = Lens {
        intrinsics,
        distortion: Distortion::default(),
    };
    let pts = points(views);
    let mut free = ALL_BUT_K3;
    free[8] = options.estimate_k3;
    let refined = refine::refine(&start, &poses, &pts, free)?;
    for (k, pose) in refined.poses.iter().enumerate() {
        check_tilt(k, pose, options)?;
    }
    // Face-on views at any distance fit any focal length (the target's size trades against it).
    if refined.poses.iter().all(|p| p.tilt_deg() < 5.0) {
        return Err(CalibError::Unconstrained {
            reason: "every view is face-on (within 5°); tilt the target 10–45° in different \
                     directions"
                .into(),
        });
    }
    let view_rms_px = views
        .iter()
        .zip(&refined.poses)
        .map(|(v, p)| view_rms(&refined.lens, p, v))
        .collect();
    Ok(Calibration {
        lens: refined.lens,
        poses: refined.poses,
        rms_px: refined.rms_px,
        view_rms_px,
    })
}

fn check_tilt(view: usize, pose: &Pose, options: &Options) -> Result<(), CalibError> {
    let tilt_deg = pose.tilt_deg();
    if tilt_deg > options.max_tilt_deg {
        return Err(CalibError::EdgeOn {
            view,
            tilt_deg,
            max_deg: options.max_tilt_deg,
        });
    }
    Ok(())
}

/// RMS reprojection error of one view, pixels.
pub fn view_rms(lens: &Lens, pose: &Pose, view: &View) -> f64 {
    let sum: f64 = view
        .target
        .iter()
        .zip(&view.image)
        .map(
            |(t, uv)| match lens.project(pose.apply(Vector3::new(t[0], t[1], 0.0))) {
                Some([u, v]) => (u - uv[0]).powi(2) + (v - uv[1]).powi(2),
                None => f64::INFINITY,
            },
        )
        .sum();
    (sum / view.target.len().max(1) as f64).sqrt()
}

/// The pose of a flat target (e.g. laid on the plate) seen in one view through a calibrated
/// lens, with its RMS reprojection error (px).
pub fn solve_pose(lens: &Lens, view: &View, options: &Options) -> Result<(Pose, f64), CalibError> {
    check_view(0, view, options)?;
    // The homography of undistorted, normalised points is [r1 r2 t] up to scale.
    let mut normalised = Vec::with_capacity(view.image.len());
    for (i, uv) in view.image.iter().enumerate() {
        let p = lens.unproject(*uv).ok_or_else(|| CalibError::Degenerate {
            view: 0,
            reason: format!("point {i} is where the lens model cannot be undone"),
        })?;
        normalised.push([p.x, p.y]);
    }
    let h = homography::fit(&view.target, &normalised).ok_or_else(|| CalibError::Degenerate {
        view: 0,
        reason: "its points lie on one line or repeat".into(),
    })?;
    let unit = crate::Intrinsics {
        fx: 1.0,
        fy: 1.0,
        cx: 0.0,
        cy: 0.0,
    };
    let start = zhang::pose(&h, &unit).ok_or_else(|| CalibError::Degenerate {
        view: 0,
        reason: "no pose fits its homography".into(),
    })?;
    check_tilt(0, &start, options)?;
    let refined = refine::refine(
        lens,
        &[start],
        &points(std::slice::from_ref(view)),
        POSES_ONLY,
    )?;
    Ok((refined.poses[0], refined.rms_px))
}

/// The point of the plane `z = 0` of the frame `pose` maps into the camera (plane → camera)
/// seen at pixel `uv`, in that plane's coordinates; `None` for a pixel whose ray misses the
/// plane (parallel, or behind the camera) or where the lens model cannot be undone.
pub fn pixel_to_plane(lens: &Lens, pose: &Pose, uv: [f64; 2]) -> Option<[f64; 2]> {
    let n = lens.unproject(uv)?;
    let r_inv = pose.rotation().inverse();
    let centre = pose.camera_centre();
    let dir = r_inv * Vector3::new(n.x, n.y, 1.0);
    if dir.z.abs() < 1e-12 {
        return None;
    }
    let s = -centre.z / dir.z;
    if s <= 0.0 {
        return None;
    }
    let p = centre + s * dir;
    Some([p.x, p.y])
}
