//! The box head of a crack-map model: boxes in the crack photos' own convention.
//!
//! The map → boxes rule ([`crate::crack_map`]) gives one box per dilated component, which is how
//! the crack datasets with masks made their boxes; photos boxed by hand (quaywall's chains of
//! small boxes along one crack, uav75's hairline pieces) are found by no such rule. The shipped
//! model (`models/detector/MODEL_CARD.md`, "The box head") therefore carries a small
//! CenterNet-style head, trained on the photos' own boxes on the frozen crack-map features, with
//! two more outputs at stride [`HEAD_STRIDE`]:
//! - `box_heat` `[1, 1, S/8, S/8]`: the probability that a box is centred in the cell;
//! - `box_reg` `[1, 4, S/8, S/8]`: the box's log width and log height in cells, and its centre's
//!   offset (x, y) from the cell's top-left corner, in cells.
//!
//! [`BoxHeadMaps::detections`] decodes them as `models/detector/contract.py`
//! (`head_to_detections`) does: one box per cell whose probability `p` is at least
//! [`HEAD_MIN_PROBABILITY`] and the largest of its 3×3 neighbourhood (ties included; cells off
//! the map do not count), best `p` first (ties in raster order); the box is centred at
//! `(c + dx, r + dy)` cells, `exp(lw) × exp(lh)` cells, scaled by `HEAD_STRIDE / s` to image
//! pixels and clipped to the image; empty boxes are dropped. Its score is
//! [`HEAD_SCORE_SCALE`]` · p`, in `[0, 0.5)`: below every component of the rule (which score at
//! least 0.5), so the head only adds boxes after the rule's. They carry
//! [`DetectionSource::BoxHead`] and no centre line: the robot does not touch them.

use crate::boxes::{BoundingBox, Detection, DetectionSource};
use crate::preprocess::{Letterbox, PostprocessParams};
use crate::VisionError;

/// Canvas pixels per cell of the head's outputs, along each axis.
pub const HEAD_STRIDE: usize = 8;
/// A peak below this probability is no box.
pub const HEAD_MIN_PROBABILITY: f32 = 0.02;
/// A head box scores this times its probability: below every crack-map component.
pub const HEAD_SCORE_SCALE: f32 = 0.5;
/// Regression channels of `box_reg`: log width, log height, offset x, offset y.
pub const REG_CHANNELS: usize = 4;

/// The box head's outputs for one letterboxed frame, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxHeadMaps {
    cells: usize,
    heat: Vec<f32>,
    reg: Vec<f32>,
    letterbox: Letterbox,
}

impl BoxHeadMaps {
    /// The outputs `box_heat` (`(S/8)²` probabilities) and `box_reg` (`4 · (S/8)²` finite
    /// values, channel-major) the model returned for the frame letterboxed as `letterbox`.
    /// Errors name the output and the value that is wrong.
    pub fn new(heat: Vec<f32>, reg: Vec<f32>, letterbox: Letterbox) -> Result<Self, VisionError> {
        let cells = letterbox.size / HEAD_STRIDE;
        if cells == 0 || heat.len() != cells * cells {
            return Err(VisionError::Shape {
                what: "the box head's `box_heat`",
                got: heat.len(),
                expected: cells * cells,
            });
        }
        if reg.len() != REG_CHANNELS * cells * cells {
            return Err(VisionError::Shape {
                what: "the box head's `box_reg`",
                got: reg.len(),
                expected: REG_CHANNELS * cells * cells,
            });
        }
        if let Some((index, &value)) = heat
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && (0.0..=1.0).contains(*v)))
        {
            return Err(VisionError::BoxHeadValue {
                output: "box_heat",
                index,
                value,
            });
        }
        if let Some((index, &value)) = reg.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(VisionError::BoxHeadValue {
                output: "box_reg",
                index,
                value,
            });
        }
        Ok(Self {
            cells,
            heat,
            reg,
            letterbox,
        })
    }

    /// Cells per side.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// The cells that are peaks: at least [`HEAD_MIN_PROBABILITY`] and the largest of their
    /// 3×3 neighbourhood, as `(probability, row, column)`, best first, ties in raster order.
    fn peaks(&self) -> Vec<(f32, usize, usize)> {
        let n = self.cells;
        let p = |r: usize, c: usize| self.heat[r * n + c];
        let mut out = Vec::new();
        for r in 0..n {
            for c in 0..n {
                let v = p(r, c);
                if v < HEAD_MIN_PROBABILITY {
                    continue;
                }
                let rows = r.saturating_sub(1)..=(r + 1).min(n - 1);
                let is_peak = rows
                    .flat_map(|rr| {
                        (c.saturating_sub(1)..=(c + 1).min(n - 1)).map(move |cc| (rr, cc))
                    })
                    .all(|(rr, cc)| p(rr, cc) <= v);
                if is_peak {
                    out.push((v, r, c));
                }
            }
        }
        // Stable: equal probabilities keep raster order.
        out.sort_by(|a, b| b.0.total_cmp(&a.0));
        out
    }

    /// The box of the peak at `(r, c)`, image pixels, clipped to the image; `None` when empty.
    fn box_at(&self, r: usize, c: usize) -> Option<BoundingBox> {
        let n = self.cells;
        let reg = |k: usize| f64::from(self.reg[(k * n + r) * n + c]);
        let lb = &self.letterbox;
        let (w, h) = (f64::from(lb.image_width), f64::from(lb.image_height));
        let (bw, bh) = (reg(0).exp(), reg(1).exp());
        let (cx, cy) = (c as f64 + reg(2), r as f64 + reg(3));
        let f = HEAD_STRIDE as f64 / f64::from(lb.scale);
        let x0 = ((cx - bw / 2.0) * f).max(0.0);
        let y0 = ((cy - bh / 2.0) * f).max(0.0);
        let x1 = ((cx + bw / 2.0) * f).min(w);
        let y1 = ((cy + bh / 2.0) * f).min(h);
        (x1 > x0 && y1 > y0).then_some(BoundingBox {
            x0: x0 as f32,
            y0: y0 as f32,
            x1: x1 as f32,
            y1: y1 as f32,
        })
    }

    /// The head's boxes (the [module docs](self)), best first: those scoring at least
    /// `params.score_threshold`, at most `params.max_detections`.
    pub fn detections(&self, params: &PostprocessParams) -> Vec<Detection> {
        self.peaks()
            .into_iter()
            .take(params.max_detections)
            .filter_map(|(p, r, c)| {
                let score = HEAD_SCORE_SCALE * p;
                let bbox = self.box_at(r, c)?;
                (score >= params.score_threshold).then_some(Detection {
                    bbox,
                    score,
                    shape: None,
                    source: DetectionSource::BoxHead,
                })
            })
            .collect()
    }
}

/// The crack map's detections followed by the box head's (which score below every one of
/// them), at most `max_detections` in all.
pub fn with_head_boxes(
    mut primary: Vec<Detection>,
    head: &BoxHeadMaps,
    params: &PostprocessParams,
) -> Vec<Detection> {
    primary.extend(head.detections(params));
    primary.truncate(params.max_detections);
    primary
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 640×480 frame at S = 64: s = 0.1, so one head cell is 80 image pixels.
    fn lb() -> Letterbox {
        Letterbox::new(640, 480, 64).unwrap()
    }

    /// Maps of 8×8 cells with the given peaks `(r, c, p)`; every box 1×2 cells, offset
    /// (0.5, 0.25).
    fn maps(peaks: &[(usize, usize, f32)]) -> BoxHeadMaps {
        let n = 8;
        let mut heat = vec![0.0; n * n];
        for &(r, c, p) in peaks {
            heat[r * n + c] = p;
        }
        let mut reg = vec![0.0; 4 * n * n];
        reg[n * n..2 * n * n].fill(2f32.ln());
        reg[2 * n * n..3 * n * n].fill(0.5);
        reg[3 * n * n..].fill(0.25);
        BoxHeadMaps::new(heat, reg, lb()).unwrap()
    }

    fn all() -> PostprocessParams {
        PostprocessParams {
            score_threshold: 0.0,
            ..PostprocessParams::default()
        }
    }

    #[test]
    fn a_peak_becomes_a_box_centred_in_its_cell_at_half_its_probability() {
        let d = maps(&[(2, 3, 0.8)]).detections(&all());
        assert_eq!(d.len(), 1);
        // Centre (3.5, 2.25) cells, 1 × 2 cells, × 80 px.
        let b = d[0].bbox;
        for (got, want) in [(b.x0, 240.0), (b.x1, 320.0), (b.y0, 100.0), (b.y1, 260.0)] {
            assert!((got - want).abs() < 1e-3, "{b:?}");
        }
        assert!((d[0].score - 0.4).abs() < 1e-6);
        assert_eq!(d[0].source, DetectionSource::BoxHead);
        assert!(d[0].shape.is_none());
    }

    #[test]
    fn only_local_maxima_above_the_floor_count_best_first_ties_in_raster_order() {
        let m = maps(&[
            (1, 1, 0.5),
            (1, 2, 0.6),  // beats its neighbour (1, 1)
            (5, 5, 0.6),  // ties with (1, 2): later in raster order
            (6, 0, 0.01), // under the floor
            (3, 6, 0.3),
            (3, 7, 0.3), // equal neighbours: both peaks
        ]);
        let d = m.detections(&all());
        let centres: Vec<[f32; 2]> = d
            .iter()
            .map(|d| [(d.bbox.x0 + d.bbox.x1) / 160.0, d.score])
            .collect();
        assert_eq!(d.len(), 4, "{centres:?}");
        assert!(
            (d[0].bbox.x0 - 160.0).abs() < 1e-3 && d[0].bbox.y0 < 100.0,
            "{d:?}"
        );
        assert!((d[1].bbox.x0 - 400.0).abs() < 1e-3, "{d:?}");
        assert!((d[2].score - 0.15).abs() < 1e-6 && (d[3].score - 0.15).abs() < 1e-6);
        // A threshold and a cap.
        let few = m.detections(&PostprocessParams {
            score_threshold: 0.2,
            max_detections: 1,
            ..all()
        });
        assert_eq!(few.len(), 1);
        assert!(m
            .detections(&PostprocessParams {
                score_threshold: 0.29,
                ..all()
            })
            .iter()
            .all(|d| d.score >= 0.29));
    }

    #[test]
    fn boxes_are_clipped_to_the_image_and_empty_ones_dropped() {
        // Row 5 of the 6 the image covers: the box reaches past its 480 px.
        let d = maps(&[(5, 7, 0.9)]).detections(&all());
        assert_eq!(d.len(), 1);
        assert!(d[0].bbox.x1 <= 640.0, "{:?}", d[0].bbox);
        assert!((d[0].bbox.y1 - 480.0).abs() < 1e-3, "{:?}", d[0].bbox);
        // Under the letterbox's padding (rows below the 480 px image): nothing left.
        let mut off = maps(&[]);
        off.heat[7 * 8] = 0.9;
        off.reg[3 * 64 + 7 * 8] = 2.0;
        off.reg[64 + 7 * 8] = 0.0;
        assert!(off.detections(&all()).is_empty());
    }

    #[test]
    fn head_boxes_follow_the_primary_ones_within_the_cap() {
        let head = maps(&[(2, 3, 0.8), (5, 5, 0.7)]);
        let primary = vec![Detection::boxed(
            BoundingBox::from_xywh(0.0, 0.0, 10.0, 10.0),
            0.6,
        )];
        let both = with_head_boxes(primary.clone(), &head, &all());
        assert_eq!(both.len(), 3);
        assert_eq!(both[0], primary[0]);
        assert!(both[1..]
            .iter()
            .all(|d| d.source == DetectionSource::BoxHead));
        let capped = with_head_boxes(
            primary,
            &head,
            &PostprocessParams {
                max_detections: 2,
                ..all()
            },
        );
        assert_eq!(capped.len(), 2);
    }

    #[test]
    fn wrong_sizes_and_values_are_named_errors() {
        let n = 64;
        let err = BoxHeadMaps::new(vec![0.0; n - 1], vec![0.0; 4 * n], lb()).unwrap_err();
        assert!(err.to_string().contains("box_heat"), "{err}");
        let err = BoxHeadMaps::new(vec![0.0; n], vec![0.0; n], lb()).unwrap_err();
        assert!(err.to_string().contains("box_reg"), "{err}");
        let mut heat = vec![0.0; n];
        heat[5] = 1.5;
        let err = BoxHeadMaps::new(heat, vec![0.0; 4 * n], lb()).unwrap_err();
        assert!(err.to_string().contains("box_heat") && err.to_string().contains("1.5"));
        let mut reg = vec![0.0; 4 * n];
        reg[9] = f32::NAN;
        let err = BoxHeadMaps::new(vec![0.0; n], reg, lb()).unwrap_err();
        assert!(matches!(
            err,
            VisionError::BoxHeadValue {
                output: "box_reg",
                index: 9,
                ..
            }
        ));
    }
}
