//! What a robot needs from its eye on rendered plates: how many cracks the detections find, and
//! how many printed decoys they propose, from the `features.json` that `crackbot-lab sim
//! detector-set` writes beside its COCO file.
//!
//! A crack is *found* by a detection when their boxes overlap with IoU ≥ 0.5, or when the box
//! holds at least [`CENTRE_LINE_INSIDE`] of the crack's visible centre line (the part of its
//! `path_px` inside its ground-truth box, sampled every pixel). Several crossing cracks are one
//! crack network in the image and one box by the datasets' rule: the second condition finds them
//! all. A decoy is *proposed* by the same test. Decoys are flat to the touch: rejecting them is
//! the tactile check's job, so proposing one is not an error, only work for the finger.

use std::collections::HashMap;

use serde::Serialize;

pub use crackbot_imaging::scene_truth::{FeatureTruth, FrameTruth, SceneTruth};

use crate::boxes::BoundingBox;
use crate::coco::{CocoDataset, CocoResult};
use crate::crack_map::CrackPiece;
use crate::pieces::PieceCounts;
use crate::VisionError;

/// Fraction of a crack's visible centre line a box must hold to find it.
pub const CENTRE_LINE_INSIDE: f64 = 0.8;

/// Crack widths the recall is broken down by, mm (upper bounds; the last bin is open).
pub const WIDTH_BINS_MM: [f64; 5] = [0.5, 1.0, 2.0, 5.0, 10.0];

/// Recall of the cracks of one width bin.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WidthRecall {
    /// Widths above this, mm.
    pub above_mm: f64,
    /// Up to this, mm (`None`: no upper bound).
    pub up_to_mm: Option<f64>,
    /// Cracks in the bin.
    pub cracks: usize,
    /// Found.
    pub found: usize,
}

/// A crack no detection found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissedCrack {
    /// The image.
    pub file: String,
    /// Its box `[x, y, w, h]`.
    pub bbox: [f64; 4],
    /// Its width, mm.
    pub width_mm: Option<f64>,
}

/// Cracks found and decoys proposed over rendered frames.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneRecall {
    /// The score a detection needs to count (the `detect` default).
    pub score_threshold: f32,
    /// What "found" means.
    pub found_is: &'static str,
    /// Frames.
    pub frames: usize,
    /// Visible cracks.
    pub cracks: usize,
    /// Cracks found (either test).
    pub found: usize,
    /// Cracks found by IoU ≥ 0.5 alone.
    pub found_by_iou: usize,
    /// `found / cracks`.
    pub recall: f64,
    /// Recall by crack width.
    pub by_width: Vec<WidthRecall>,
    /// Visible printed decoys.
    pub decoys: usize,
    /// Decoys a detection proposes.
    pub decoys_proposed: usize,
    /// Detections that find neither a crack nor a decoy.
    pub other_detections: usize,
    /// Detections counted.
    pub detections: usize,
    /// The cracks missed.
    pub missed: Vec<MissedCrack>,
    /// How the pieces the robot would touch fall on the cracks (detectors with a crack map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pieces: Option<PieceCounts>,
}

/// Whether detection box `det` finds the feature `f`.
fn finds(det: &BoundingBox, f: &FeatureTruth) -> (bool, bool) {
    let [x, y, w, h] = f.bbox;
    let gt = BoundingBox::from_xywh(x as f32, y as f32, w as f32, h as f32);
    let by_iou = det.iou(&gt) >= 0.5;
    if by_iou {
        return (true, true);
    }
    let Some(path) = f.path_px.as_deref() else {
        return (false, false);
    };
    let (mut visible, mut inside) = (0usize, 0usize);
    let in_box = |p: [f64; 2], b: &BoundingBox, pad: f64| {
        p[0] >= f64::from(b.x0) - pad
            && p[0] <= f64::from(b.x1) + pad
            && p[1] >= f64::from(b.y0) - pad
            && p[1] <= f64::from(b.y1) + pad
    };
    // Segments with an end behind the camera have no pixels.
    for seg in path.windows(2) {
        let (Some(a), Some(b)) = (seg[0], seg[1]) else {
            continue;
        };
        let n = ((b[0] - a[0]).hypot(b[1] - a[1]).ceil() as usize).max(1);
        for k in 0..n {
            let t = k as f64 / n as f64;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            if in_box(p, &gt, 1.0) {
                visible += 1;
                if in_box(p, det, 1.0) {
                    inside += 1;
                }
            }
        }
    }
    let by_line = visible > 0 && inside as f64 >= CENTRE_LINE_INSIDE * visible as f64;
    (by_line, false)
}

/// Scores `results` (detections as COCO results, e.g. of a [`crate::benchmark::Benchmark`]
/// run) against `truth` for the frames of `gt`, counting detections scoring at least
/// `score_threshold`; with `pieces` (image id → the pieces of those detections) also how the
/// pieces fall on the cracks ([`PieceCounts`]). Errors when a frame of `gt` has no entry in
/// `truth`.
pub fn scene_recall(
    gt: &CocoDataset,
    truth: &SceneTruth,
    results: &[CocoResult],
    score_threshold: f32,
    pieces: Option<&HashMap<u64, Vec<CrackPiece>>>,
) -> Result<SceneRecall, VisionError> {
    let mut bins: Vec<WidthRecall> = WIDTH_BINS_MM
        .iter()
        .enumerate()
        .map(|(i, &hi)| WidthRecall {
            above_mm: if i == 0 { 0.0 } else { WIDTH_BINS_MM[i - 1] },
            up_to_mm: Some(hi),
            cracks: 0,
            found: 0,
        })
        .collect();
    bins.push(WidthRecall {
        above_mm: WIDTH_BINS_MM[WIDTH_BINS_MM.len() - 1],
        up_to_mm: None,
        cracks: 0,
        found: 0,
    });
    let mut out = SceneRecall {
        score_threshold,
        found_is: "IoU >= 0.5 with a detection box, or >= 80% of the crack's visible centre line inside one",
        frames: gt.images.len(),
        cracks: 0,
        found: 0,
        found_by_iou: 0,
        recall: 1.0,
        by_width: Vec::new(),
        decoys: 0,
        decoys_proposed: 0,
        other_detections: 0,
        detections: 0,
        missed: Vec::new(),
        pieces: pieces.map(|_| PieceCounts::default()),
    };
    for image in &gt.images {
        let frame = truth
            .images
            .iter()
            .find(|f| f.file_name == image.file_name)
            .ok_or_else(|| VisionError::MissingFrame {
                file_name: image.file_name.clone(),
            })?;
        let dets: Vec<BoundingBox> = results
            .iter()
            .filter(|r| r.image_id == image.id && r.score >= f64::from(score_threshold))
            .map(|r| {
                let [x, y, w, h] = r.bbox;
                BoundingBox::from_xywh(x as f32, y as f32, w as f32, h as f32)
            })
            .collect();
        out.detections += dets.len();
        let mut useful = vec![false; dets.len()];
        let mut held = vec![false; frame.boxes.len()];
        for (i, f) in frame.boxes.iter().enumerate() {
            let is_crack = f.kind == "crack";
            if !(is_crack || f.kind == "decoy") {
                continue;
            }
            let mut found = false;
            let mut by_iou = false;
            for (k, d) in dets.iter().enumerate() {
                let (hit, iou) = finds(d, f);
                if hit {
                    useful[k] = true;
                    found = true;
                    by_iou |= iou;
                }
            }
            held[i] = found;
            if is_crack {
                out.cracks += 1;
                out.found += usize::from(found);
                out.found_by_iou += usize::from(by_iou);
                let w = f.width_mm.unwrap_or(f64::NAN);
                let bin = WIDTH_BINS_MM
                    .iter()
                    .position(|&hi| w <= hi)
                    .unwrap_or(WIDTH_BINS_MM.len());
                bins[bin].cracks += 1;
                bins[bin].found += usize::from(found);
                if !found {
                    out.missed.push(MissedCrack {
                        file: image.file_name.clone(),
                        bbox: f.bbox,
                        width_mm: f.width_mm,
                    });
                }
            } else {
                out.decoys += 1;
                out.decoys_proposed += usize::from(found);
            }
        }
        out.other_detections += useful.iter().filter(|u| !**u).count();
        if let (Some(counts), Some(pieces)) = (out.pieces.as_mut(), pieces) {
            let own = pieces.get(&image.id).map_or(&[][..], Vec::as_slice);
            counts.add_frame(frame, own, &held);
        }
    }
    if out.cracks > 0 {
        out.recall = out.found as f64 / out.cracks as f64;
    }
    out.by_width = bins.into_iter().filter(|b| b.cracks > 0).collect();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coco::CocoImage;

    fn feature(kind: &str, bbox: [f64; 4], path: &[[f64; 2]], width: f64) -> FeatureTruth {
        FeatureTruth {
            kind: kind.into(),
            feature_index: 0,
            bbox,
            pixels: 1,
            width_mm: Some(width),
            path_px: Some(path.iter().map(|&p| Some(p)).collect()),
            path_mm: None,
            centre_mm: None,
        }
    }

    fn frame(file_name: &str, boxes: Vec<FeatureTruth>) -> FrameTruth {
        FrameTruth {
            file_name: file_name.into(),
            width: 100,
            height: 100,
            seed: 0,
            scene_seed: 0,
            material: "PLA".into(),
            plate_to_image: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            boxes,
        }
    }

    fn result(bbox: [f64; 4], score: f64) -> CocoResult {
        CocoResult {
            image_id: 1,
            category_id: 1,
            bbox,
            score,
        }
    }

    #[test]
    fn cracks_are_found_by_iou_or_by_their_centre_line_and_decoys_are_counted() {
        let gt = CocoDataset {
            info: None,
            images: vec![CocoImage::new(1, "a.png", 100, 100)],
            annotations: vec![],
            categories: vec![],
        };
        let truth = SceneTruth {
            description: String::new(),
            images: vec![frame(
                "a.png",
                vec![
                    // Found by IoU.
                    feature(
                        "crack",
                        [10.0, 10.0, 20.0, 4.0],
                        &[[10.0, 12.0], [30.0, 12.0]],
                        2.0,
                    ),
                    // Inside a big box (a crack network): found by its centre line.
                    feature(
                        "crack",
                        [50.0, 50.0, 10.0, 10.0],
                        &[[50.0, 50.0], [60.0, 60.0]],
                        0.6,
                    ),
                    // Missed.
                    feature(
                        "crack",
                        [5.0, 80.0, 10.0, 2.0],
                        &[[5.0, 81.0], [15.0, 81.0]],
                        0.3,
                    ),
                    feature(
                        "decoy",
                        [70.0, 10.0, 10.0, 2.0],
                        &[[70.0, 11.0], [80.0, 11.0]],
                        1.0,
                    ),
                    FeatureTruth {
                        kind: "screw".into(),
                        path_px: None,
                        width_mm: None,
                        centre_mm: Some([1.0, 1.0]),
                        ..feature("screw", [0.0, 0.0, 5.0, 5.0], &[], 0.0)
                    },
                ],
            )],
        };
        let results = vec![
            result([10.0, 10.0, 20.0, 5.0], 0.9),
            result([40.0, 40.0, 50.0, 50.0], 0.8),
            result([69.0, 9.0, 12.0, 4.0], 0.7),
            result([0.0, 90.0, 5.0, 5.0], 0.6),
            result([5.0, 80.0, 10.0, 2.0], 0.1), // below the threshold: does not count
        ];
        let r = scene_recall(&gt, &truth, &results, 0.25, None).unwrap();
        assert_eq!((r.cracks, r.found, r.found_by_iou), (3, 2, 1));
        assert!((r.recall - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!((r.decoys, r.decoys_proposed), (1, 1));
        assert_eq!((r.detections, r.other_detections), (4, 1));
        assert_eq!(r.missed.len(), 1);
        assert_eq!(r.missed[0].width_mm, Some(0.3));
        let first = &r.by_width[0];
        assert_eq!((first.above_mm, first.cracks, first.found), (0.0, 1, 0));
        let missing = SceneTruth {
            description: String::new(),
            images: vec![],
        };
        assert!(scene_recall(&gt, &missing, &results, 0.25, None).is_err());
    }
}
