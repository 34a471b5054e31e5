//! `crackbot-imaging`: the few image-side definitions that the simulator and the vision crate
//! share, each defined once.
//!
//! * [`homography`]: applying a plane homography between image pixels and surface millimetres,
//!   with an explicit policy for points at or behind the horizon
//!   ([`homography::apply_in_front`], [`homography::apply_finite`]), and the validated
//!   pixel → surface [`Homography`] with its inverse and reprojection errors.
//! * [`coco`]: COCO detection files (ground truth and results): the types, reading, validating
//!   and writing them. crackbot's own extensions (the simulator's seed, homography and
//!   per-crack fields, the photo datasets' mask files) are typed optional fields.
//! * [`scene_truth`]: a detector set's `features.json` (every crack, decoy and screw of every
//!   rendered frame), written by the simulator and read by the detector's evaluation.
//! * [`geometry`]: distances between surface points, segments and polylines.
//! * [`thinning`]: binary images thinned to one-pixel centre lines (the planner's eq. 1 on
//!   crack masks, the vision crate's touch points along a detected crack).
//!
//! The crate is deliberately light (nalgebra, serde, serde_json, thiserror): no image decoding,
//! no runtime.

pub mod coco;
mod error;
pub mod geometry;
pub mod homography;
pub mod scaled_png;
pub mod scene_truth;
pub mod thinning;

pub use error::ImagingError;
pub use homography::{Homography, PointPair, ReprojectionStats};
