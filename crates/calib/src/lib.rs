//! `crackbot-calib`: the camera's lens and pose from views of a flat target with known points.
//!
//! * [`lens`]: the model, OpenCV's: a pinhole (`fx`, `fy`, `cx`, `cy`) and Brown–Conrady
//!   distortion in OpenCV's order (`k1`, `k2`, `p1`, `p2`, `k3`), projecting camera-frame points
//!   to pixels and undoing the distortion of a pixel (Newton's method, checked).
//! * [`pose`]: rigid poses (rotation vector + translation), a plane's pose from its homography.
//! * [`zhang`]: the closed-form start, Zhang (2000): a homography per view, the intrinsics from
//!   their constraints (zero skew), each view's pose.
//! * [`refine`]: Levenberg–Marquardt over the intrinsics, the distortion and every view's pose,
//!   minimising the reprojection error in pixels.
//! * [`calibrate`]: the whole fit, with its checks: enough views and points, finite numbers, no
//!   view edge-on, views tilted enough to constrain the focal lengths; [`calibrate::solve_pose`]
//!   finds a plane's pose (the target laid on the plate) through the lens, and
//!   [`calibrate::pixel_to_plane`] maps a pixel to a point on that plane.
//! * [`file`]: the calibration file (TOML, `docs/calibration-file.md`): image size, lens in
//!   OpenCV's terms, the plate's pose, the errors, the date; checked field by field on loading,
//!   and against every frame's size.
//!
//! * [`undistort`]: the frame as the pinhole sees it (a map made once, a bilinear lookup per
//!   frame) and the plate → undistorted-pixel homography, which is how missions use the lens.
//!
//! Pixels are whatever convention the caller's points use (crackbot's: the top-left corner of
//! the top-left pixel is `(0, 0)`; OpenCV's: its centre is, so OpenCV's `cx` is crackbot's
//! minus 0.5). Target points are millimetres on the target's plane (z = 0).
//!
//! No I/O beyond the calibration file; images only in [`undistort`].

pub mod calibrate;
mod error;
pub mod file;
pub mod homography;
pub mod lens;
pub mod pose;
pub mod refine;
pub mod undistort;
pub mod zhang;

pub use calibrate::{calibrate, Calibration, Options, View};
pub use error::CalibError;
pub use file::{CameraFile, FileError};
pub use lens::{Distortion, Intrinsics, Lens};
pub use pose::Pose;
pub use undistort::Undistorter;
