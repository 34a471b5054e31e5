//! Finding candidate cracks in a camera frame and saying where they are on the work surface.
//!
//! * [`Detector`]: one trait for every detector, returning [`Detection`]s in image pixels.
//!   - `onnx` (cargo feature `onnx`): the crack detector trained in `models/detector/`, run through
//!     ONNX Runtime (`ort`, loaded at run time).
//!   - [`classical`]: an edge-based baseline (no model, no runtime).
//! * [`preprocess`]: the letterbox contract shared with the model (`models/detector/MODEL_CARD.md`).
//! * [`boxes`]: boxes, IoU, non-maximum suppression.
//! * [`box_head`]: the boxes of a crack-map model's box head (boxes in the photos' own
//!   convention, below the crack map's).
//! * [`crack_map`]: detections from a segmentation detector's crack map (boxes by the crack
//!   datasets' rule, each crack's main axis and centre line).
//! * Evaluation, behind the cargo feature `research` (never in the robot's build): `coco`, COCO
//!   files and the COCO detection metrics (mAP@[.5:.95], mAP@0.5, AR@100) as pycocotools
//!   computes them; `pixel`, pixel-level precision, recall and F1 (ODS, OIS) of a crack map
//!   against a mask; `scene_recall` and `pieces`, cracks found, decoys proposed and cracks in one
//!   piece on rendered plates (`features.json`); `benchmark`, a detector over a COCO ground truth
//!   and the `crackbot-lab eval-detector` report; `tradeoff`, accuracy against run time.
//! * [`fusion`]: combining detections over several frames of one view.
//! * [`homography`]: pixel ↔ surface millimetres from point pairs (normalised DLT, RANSAC), its
//!   calibration file, and the point-pairs CSV reader.
//! * [`detect`]: the `crackbot detect` flow (threshold, surface mm, fusion, annotated images) and
//!   its report; [`model`]: where the trained model is.

#[cfg(feature = "research")]
pub mod benchmark;
pub mod box_head;
pub mod boxes;
pub mod camera;
pub mod classical;
#[cfg(feature = "research")]
pub mod coco;
pub mod crack_map;
pub mod crack_recall;
pub mod detect;
mod error;
pub mod fusion;
pub mod homography;
pub mod model;
#[cfg(feature = "onnx")]
pub mod onnx;
#[cfg(feature = "research")]
pub mod pieces;
#[cfg(feature = "research")]
pub mod pixel;
pub mod preprocess;
#[cfg(feature = "research")]
pub mod scene_recall;
pub mod shape;
#[cfg(feature = "research")]
pub mod tradeoff;

pub use boxes::{BoundingBox, Detection, DetectionSource};
pub use error::VisionError;

/// Anything that finds cracks in an RGB frame.
pub trait Detector {
    /// Short name for reports (e.g. `"onnx:crack-detector-320"`, `"classical"`).
    fn name(&self) -> String;

    /// Candidate cracks in `image`, boxes in the image's pixel coordinates (x right, y down, origin
    /// at the top-left corner of the top-left pixel), scores in `[0, 1]`, best first.
    fn detect(&mut self, image: &image::RgbImage) -> Result<Vec<Detection>, VisionError>;

    /// [`Detector::detect`], with the crack map behind the detections for detectors that
    /// predict one (pixel-level evaluation); the default has no map.
    fn detect_with_map(
        &mut self,
        image: &image::RgbImage,
    ) -> Result<(Vec<Detection>, Option<crack_map::CrackMap>), VisionError> {
        Ok((self.detect(image)?, None))
    }
}
