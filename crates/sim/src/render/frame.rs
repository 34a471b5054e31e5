//! What the renderer produces: a frame, its ground-truth boxes, and the accumulator that finds a
//! feature's tight box while its pixels are drawn.

use image::{GrayImage, RgbImage};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// What a ground-truth box marks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxKind {
    /// A crack (the only kind annotated in COCO exports).
    Crack,
    /// A printed decoy crack.
    Decoy,
    /// A screw head.
    Screw,
}

impl BoxKind {
    /// The kind's name: `"crack"`, `"decoy"` or `"screw"`.
    pub fn as_str(self) -> &'static str {
        match self {
            BoxKind::Crack => "crack",
            BoxKind::Decoy => "decoy",
            BoxKind::Screw => "screw",
        }
    }
}

/// The ground-truth box of one visible feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruthBox {
    /// What it is.
    pub kind: BoxKind,
    /// Index of the feature in the scene's `features`.
    pub feature_index: usize,
    /// Left edge, pixels (the leftmost pixel's column).
    pub x: f64,
    /// Top edge, pixels (the topmost pixel's row).
    pub y: f64,
    /// Width, pixels.
    pub w: f64,
    /// Height, pixels.
    pub h: f64,
    /// Number of visible pixels of the feature (mask above 0.5, not occluded).
    pub pixels: u64,
    /// The feature's width on the plate, mm (cracks and decoys).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_mm: Option<f64>,
}

impl GroundTruthBox {
    /// `[x, y, w, h]`.
    pub fn bbox(&self) -> [f64; 4] {
        [self.x, self.y, self.w, self.h]
    }

    /// Whether the pixel coordinates `uv` fall inside the box.
    pub fn contains(&self, uv: [f64; 2]) -> bool {
        uv[0] >= self.x && uv[0] <= self.x + self.w && uv[1] >= self.y && uv[1] <= self.y + self.h
    }
}

/// A rendered camera frame with its ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The image.
    pub image: RgbImage,
    /// Boxes of the visible cracks, decoys and screws, in feature order.
    pub boxes: Vec<GroundTruthBox>,
    /// Per-pixel crack mask, the image's size: 255 where a crack (not a decoy, not a screw) is
    /// visible, exactly the pixels its ground-truth box is built from (the crack's mask above
    /// 0.5 and no screw covering it), 0 elsewhere. Each crack box is the tight box of its pixels.
    pub crack_mask: GrayImage,
    /// The exact homography from plate mm (z = 0) to pixels.
    pub plate_to_image: Matrix3<f64>,
    /// The seed the frame was rendered with.
    pub seed: u64,
}

impl Frame {
    /// The boxes of one kind.
    pub fn boxes_of(&self, kind: BoxKind) -> impl Iterator<Item = &GroundTruthBox> + '_ {
        self.boxes.iter().filter(move |b| b.kind == kind)
    }
}

/// Running bounding box of a feature's visible pixels.
#[derive(Clone, Copy)]
pub(super) struct BoxAcc {
    c0: usize,
    c1: usize,
    r0: usize,
    r1: usize,
    n: u64,
}

impl BoxAcc {
    pub(super) fn new() -> BoxAcc {
        BoxAcc {
            c0: usize::MAX,
            c1: 0,
            r0: usize::MAX,
            r1: 0,
            n: 0,
        }
    }
    pub(super) fn add(&mut self, c: usize, r: usize) {
        self.c0 = self.c0.min(c);
        self.c1 = self.c1.max(c);
        self.r0 = self.r0.min(r);
        self.r1 = self.r1.max(r);
        self.n += 1;
    }
    pub(super) fn finish(
        self,
        kind: BoxKind,
        feature_index: usize,
        width_mm: Option<f64>,
    ) -> Option<GroundTruthBox> {
        (self.n > 0).then(|| GroundTruthBox {
            kind,
            feature_index,
            x: self.c0 as f64,
            y: self.r0 as f64,
            w: (self.c1 - self.c0 + 1) as f64,
            h: (self.r1 - self.r0 + 1) as f64,
            pixels: self.n,
            width_mm,
        })
    }
}
