//! Camera images of a scene with ground truth: what the robot's camera would see of the plate,
//! the tight boxes of every visible crack, decoy and screw, and the exact plate → image
//! homography.
//!
//! Every pixel is mapped back through the camera's image → plate homography:
//! * off the plate: a dark background;
//! * on it: the material's colour modulated by value noise (a procedural texture), shaded by the
//!   height field of bumps and wavy patches (Lambertian, one light whose direction is drawn per
//!   frame);
//! * cracks carry **real crack appearance**: a crack photographed in the real datasets
//!   (`crackforest`, `uav75`, training split only) is cut out along its principal direction and
//!   straightened into a strip (photo and mask), and the strip is warped along the scene crack's
//!   polyline: arc length `s` along the path maps to the strip's length, the signed distance `d`
//!   across it to the strip's width, scaled so the crack is `width_mm` wide on the plate. The
//!   photo's darkening (pixel over local background) is applied to the plate's colour through the
//!   mask, stronger for deeper cracks, with the groove's wall shadow on the lit side. A zero-width
//!   crack is drawn as a faint one-pixel hairline.
//! * decoys (printed cracks) use the same warped masks but flat ink (the plate colour times the
//!   decoy's reflectivity), without texture or shadow;
//! * screws are drawn last as metal discs with a slot, at their head's height, occluding what is
//!   under them.
//!
//! Then the frame's lighting (gain, a linear gradient and a vignette, whose strength is the
//! camera's `lighting_variation`) and Gaussian sensor noise (`noise_sigma`) are applied. Everything
//! is deterministic from the seed.
//!
//! Ground-truth boxes are COCO-style `[x, y, w, h]` pixel boxes (top-left origin, tight around the
//! pixels, `w = max col − min col + 1`) of the pixels where a crack's or decoy's (unsoftened) mask
//! exceeds 0.5 and no screw covers it; a screw's box is its visible disc. Features that do not
//! show in the image get no box. The frame's crack mask is exactly the cracks' such pixels (not
//! the decoys'), so each crack box is the tight box of its mask pixels.
//!
//! The parts: `assets` (the real crack strips), `texture` (procedural
//! texture, noise, shading), `geometry`, `draw` (the renderer's steps), `frame` (frames and
//! ground-truth boxes), `export` (PNG, JSON and COCO files), `dataset` (a run of frames
//! written as a COCO dataset) and `detector_set` (frames of many random scenes with per-pixel
//! crack masks, for training and evaluating a crack detector); `sheet`, a printed calibration
//! target lying on the plate seen through the camera's lens, at the poses of a calibration.

mod assets;
mod dataset;
mod detector_set;
mod draw;
mod export;
mod frame;
mod geometry;
mod sheet;
mod texture;

pub use assets::{CrackAssets, CrackStrip, CRACKS_DIR_ENV, CRACK_DATASETS};
pub use dataset::{render_dataset, RenderSummary};
pub use detector_set::{detector_frame_seed, write_detector_set, DetectorSetSummary};
pub use draw::{render, RenderOptions, SCREW_GREY};
pub use export::{coco_dataset, coco_file, frame_json, write_coco_dataset, write_frame};
pub use frame::{BoxKind, Frame, GroundTruthBox};
pub use sheet::{calibration_poses, render_sheet, SheetOptions};
