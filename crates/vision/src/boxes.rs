//! Axis-aligned boxes, intersection over union and non-maximum suppression.

use serde::{Deserialize, Serialize};

/// An axis-aligned box in pixels: `x0 <= x1`, `y0 <= y1` (corners, continuous coordinates: a box
/// covering exactly pixel (0, 0) is `0, 0, 1, 1`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoundingBox {
    /// Left edge.
    pub x0: f32,
    /// Top edge.
    pub y0: f32,
    /// Right edge.
    pub x1: f32,
    /// Bottom edge.
    pub y1: f32,
}

impl BoundingBox {
    /// A box from COCO's `[x, y, width, height]`.
    pub fn from_xywh(x: f32, y: f32, w: f32, h: f32) -> Self {
        Self {
            x0: x,
            y0: y,
            x1: x + w,
            y1: y + h,
        }
    }

    /// COCO's `[x, y, width, height]`.
    pub fn to_xywh(&self) -> [f32; 4] {
        [self.x0, self.y0, self.width(), self.height()]
    }

    /// Width (0 when degenerate).
    pub fn width(&self) -> f32 {
        (self.x1 - self.x0).max(0.0)
    }

    /// Height (0 when degenerate).
    pub fn height(&self) -> f32 {
        (self.y1 - self.y0).max(0.0)
    }

    /// Area (0 when degenerate).
    pub fn area(&self) -> f32 {
        self.width() * self.height()
    }

    /// Length of the diagonal (0 for an empty or inverted box).
    pub fn diagonal(&self) -> f32 {
        (self.x1 - self.x0)
            .max(0.0)
            .hypot((self.y1 - self.y0).max(0.0))
    }

    /// Centre point.
    pub fn centre(&self) -> (f32, f32) {
        ((self.x0 + self.x1) / 2.0, (self.y0 + self.y1) / 2.0)
    }

    /// Whether all four coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.x0.is_finite() && self.y0.is_finite() && self.x1.is_finite() && self.y1.is_finite()
    }

    /// The box clipped to `[0, width] × [0, height]`.
    pub fn clipped(&self, width: f32, height: f32) -> Self {
        Self {
            x0: self.x0.clamp(0.0, width),
            y0: self.y0.clamp(0.0, height),
            x1: self.x1.clamp(0.0, width),
            y1: self.y1.clamp(0.0, height),
        }
    }

    /// Intersection over union (0 when either box is empty).
    pub fn iou(&self, other: &Self) -> f32 {
        let iw = (self.x1.min(other.x1) - self.x0.max(other.x0)).max(0.0);
        let ih = (self.y1.min(other.y1) - self.y0.max(other.y0)).max(0.0);
        let inter = iw * ih;
        let union = self.area() + other.area() - inter;
        if union > 0.0 {
            inter / union
        } else {
            0.0
        }
    }
}

/// Which part of a detector found a detection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectionSource {
    /// The detector's own boxes: a crack-map component by the datasets' rule (with its centre
    /// line), a box model's row, the edge baseline's box.
    #[default]
    Primary,
    /// A crack-map model's box head ([`crate::box_head`]): a box in the crack photos' own
    /// convention, with no centre line, scored below every component. For box metrics and
    /// reports; the robot does not touch it (it was never checked on the rendered scenes).
    BoxHead,
}

impl DetectionSource {
    /// Whether this is [`DetectionSource::Primary`] (for `skip_serializing_if`).
    pub fn is_primary(&self) -> bool {
        *self == DetectionSource::Primary
    }
}

/// One candidate crack.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Where, in image pixels.
    pub bbox: BoundingBox,
    /// Confidence in `[0, 1]`.
    pub score: f32,
    /// Where the crack runs inside the box (detectors that predict a crack map; `None` for box
    /// detectors).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<crate::shape::CrackShape>,
    /// Which part of the detector found it.
    #[serde(default, skip_serializing_if = "DetectionSource::is_primary")]
    pub source: DetectionSource,
}

impl Detection {
    /// A detection with a box and a score only.
    pub fn boxed(bbox: BoundingBox, score: f32) -> Self {
        Self {
            bbox,
            score,
            shape: None,
            source: DetectionSource::Primary,
        }
    }
}

/// Greedy non-maximum suppression: keeps detections best score first, dropping any whose IoU with
/// a kept one exceeds `iou_threshold`; at most `max_detections`. Ties in score keep input order.
/// Non-finite boxes or scores are dropped.
pub fn nms(
    mut detections: Vec<Detection>,
    iou_threshold: f32,
    max_detections: usize,
) -> Vec<Detection> {
    detections.retain(|d| d.bbox.is_finite() && d.score.is_finite());
    detections.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut kept: Vec<Detection> = Vec::new();
    for d in detections {
        if kept.len() >= max_detections {
            break;
        }
        if kept.iter().all(|k| k.bbox.iou(&d.bbox) <= iou_threshold) {
            kept.push(d);
        }
    }
    kept
}

/// A detection from its corners and score (shared by the crate's tests).
#[cfg(test)]
pub(crate) fn det(x0: f32, y0: f32, x1: f32, y1: f32, score: f32) -> Detection {
    Detection::boxed(BoundingBox { x0, y0, x1, y1 }, score)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iou_of_known_boxes() {
        let a = BoundingBox::from_xywh(0.0, 0.0, 10.0, 10.0);
        let b = BoundingBox::from_xywh(5.0, 0.0, 10.0, 10.0);
        assert!((a.iou(&b) - 50.0 / 150.0).abs() < 1e-6);
        assert_eq!(a.iou(&a), 1.0);
        assert_eq!(a.iou(&BoundingBox::from_xywh(20.0, 20.0, 1.0, 1.0)), 0.0);
        assert_eq!(a.iou(&BoundingBox::from_xywh(1.0, 1.0, 0.0, 0.0)), 0.0);
        assert_eq!(a.to_xywh(), [0.0, 0.0, 10.0, 10.0]);
    }

    #[test]
    fn nms_keeps_the_best_of_each_cluster() {
        let kept = nms(
            vec![
                det(0.0, 0.0, 10.0, 10.0, 0.8),
                det(1.0, 1.0, 11.0, 11.0, 0.9),
                det(50.0, 50.0, 60.0, 60.0, 0.5),
                det(f32::NAN, 0.0, 1.0, 1.0, 0.99),
                det(0.0, 0.0, 1.0, 1.0, f32::NAN),
            ],
            0.5,
            10,
        );
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[0].score, 0.9);
        assert_eq!(kept[1].score, 0.5);
        assert_eq!(nms(kept.clone(), 0.5, 1).len(), 1);
    }
}
