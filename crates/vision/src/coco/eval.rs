//! The COCO detection metrics, computed exactly as pycocotools' `COCOeval` (iouType `bbox`)
//! does.
//!
//! Conventions:
//! * Boxes are COCO's `[x, y, width, height]` in pixels (origin at the top-left corner of the
//!   image), kept as `f64` like pycocotools keeps them, so that IoUs and thresholds compare
//!   bit for bit the same way.
//! * IoU is computed on `xywh` boxes without a `+1` (pycocotools' `maskUtils.iou`); a ground-truth
//!   box marked `iscrowd` is matched by "intersection over the detection's area" and may be matched
//!   by several detections; detections matched to a crowd box are ignored.
//! * The ground-truth area ranges (small < 32², medium 32²–96², large > 96²) use the annotation's
//!   `area` field; a detection's area is `w * h`.
//! * Detections are ranked with a *stable* sort on descending score (pycocotools' mergesort on
//!   `-score`): ties keep the order of the results file within an image, and image-id order across
//!   images. Per image and category only the `maxDet` best are kept.
//! * Entries without any (non-ignored) ground truth are `-1` and are left out of the means, as in
//!   pycocotools; a metric for which every entry is `-1` is itself `-1`.
//! * Results whose category is not a ground-truth category are ignored (pycocotools' behaviour).
//! * One known quirk is reproduced on purpose: pycocotools records a match as the matched
//!   ground-truth annotation's id and treats id 0 as "no match", so a detection matched to a
//!   ground-truth annotation with id 0 counts as a false positive.

use std::collections::HashMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::{validate_results, CocoAnnotation, CocoDataset, CocoResult};
use crate::VisionError;

/// The twelve numbers of pycocotools' `COCOeval.summarize()` (`-1` where undefined).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CocoMetrics {
    /// AP @ IoU .50:.05:.95, all areas, 100 detections.
    pub map: f64,
    /// AP @ IoU .50, all areas, 100 detections.
    pub map50: f64,
    /// AP @ IoU .75, all areas, 100 detections.
    pub map75: f64,
    /// AP for small ground truth (area < 32²).
    pub map_small: f64,
    /// AP for medium ground truth (32² ≤ area ≤ 96²).
    pub map_medium: f64,
    /// AP for large ground truth (area > 96²).
    pub map_large: f64,
    /// AR with 1 detection per image.
    pub ar1: f64,
    /// AR with 10 detections per image.
    pub ar10: f64,
    /// AR with 100 detections per image.
    pub ar100: f64,
    /// AR for small ground truth, 100 detections.
    pub ar_small: f64,
    /// AR for medium ground truth, 100 detections.
    pub ar_medium: f64,
    /// AR for large ground truth, 100 detections.
    pub ar_large: f64,
}

impl CocoMetrics {
    /// Names of [`CocoMetrics::stats`], in `COCOeval.stats` order.
    pub const NAMES: [&'static str; 12] = [
        "map",
        "map50",
        "map75",
        "map_small",
        "map_medium",
        "map_large",
        "ar1",
        "ar10",
        "ar100",
        "ar_small",
        "ar_medium",
        "ar_large",
    ];

    /// The metrics in `COCOeval.stats` order.
    pub fn stats(&self) -> [f64; 12] {
        [
            self.map,
            self.map50,
            self.map75,
            self.map_small,
            self.map_medium,
            self.map_large,
            self.ar1,
            self.ar10,
            self.ar100,
            self.ar_small,
            self.ar_medium,
            self.ar_large,
        ]
    }
}

/// pycocotools' IoU thresholds (`np.linspace(.5, .95, 10)`, bit for bit).
fn iou_thresholds() -> [f64; 10] {
    let step = (0.95 - 0.5) / 9.0;
    let mut t = [0.0; 10];
    for (i, v) in t.iter_mut().enumerate() {
        *v = i as f64 * step + 0.5;
    }
    t[9] = 0.95;
    t
}

/// pycocotools' recall points (`np.linspace(0, 1, 101)`, bit for bit).
fn recall_thresholds() -> [f64; 101] {
    let mut r = [0.0; 101];
    for (i, v) in r.iter_mut().enumerate() {
        *v = i as f64 * 0.01;
    }
    r[100] = 1.0;
    r
}

const MAX_DETS: [usize; 3] = [1, 10, 100];
const AREA_RANGES: [(f64, f64); 4] = [
    (0.0, 1e10),
    (0.0, 32.0 * 32.0),
    (32.0 * 32.0, 96.0 * 96.0),
    (96.0 * 96.0, 1e10),
];

/// `maskUtils.iou` for boxes (`bbIou` in pycocotools' C code).
fn coco_iou(d: &[f64; 4], g: &[f64; 4], crowd: bool) -> f64 {
    let da = d[2] * d[3];
    let ga = g[2] * g[3];
    let w = (d[2] + d[0]).min(g[2] + g[0]) - d[0].max(g[0]);
    if w <= 0.0 {
        return 0.0;
    }
    let h = (d[3] + d[1]).min(g[3] + g[1]) - d[1].max(g[1]);
    if h <= 0.0 {
        return 0.0;
    }
    let i = w * h;
    let u = if crowd { da } else { da + ga - i };
    i / u
}

/// `COCOeval.evaluateImg` output for one image, category and area range.
struct EvalImg {
    /// Scores of the kept detections, best first.
    dt_scores: Vec<f64>,
    /// `[t][d]`: matched ground-truth id (0 = none).
    dt_matches: Vec<Vec<u64>>,
    /// `[t][d]`: ignored detection.
    dt_ignore: Vec<Vec<bool>>,
    /// Per ground truth: ignored.
    gt_ignore: Vec<bool>,
}

/// Ground truth, detections (sorted, truncated) and their IoUs for one image and category.
type ImageGroup<'g, 'd> = (&'g Vec<GtRef<'d>>, &'g Vec<&'d CocoResult>, Vec<Vec<f64>>);

struct GtRef<'a> {
    ann: &'a CocoAnnotation,
}

fn stable_order_by_score_desc(scores: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..scores.len()).collect();
    // `sort_by` is stable, like numpy's mergesort on `-score`.
    idx.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    idx
}

fn evaluate_img(
    gts: &[GtRef<'_>],
    dts: &[&CocoResult],
    ious: &[Vec<f64>],
    area: (f64, f64),
    max_det: usize,
    thresholds: &[f64; 10],
) -> Option<EvalImg> {
    if gts.is_empty() && dts.is_empty() {
        return None;
    }
    let ignore_of =
        |g: &GtRef<'_>| g.ann.iscrowd != 0 || g.ann.area < area.0 || g.ann.area > area.1;
    // Stable sort: non-ignored ground truth first.
    let mut gt_order: Vec<usize> = (0..gts.len()).collect();
    gt_order.sort_by_key(|&i| ignore_of(&gts[i]));
    let gt_ignore: Vec<bool> = gt_order.iter().map(|&i| ignore_of(&gts[i])).collect();
    let crowd: Vec<bool> = gt_order.iter().map(|&i| gts[i].ann.iscrowd != 0).collect();
    // `dts` is already sorted by score and truncated to maxDets[-1]; keep the first max_det.
    let d_count = dts.len().min(max_det);
    let t_count = thresholds.len();
    let mut gt_matched = vec![vec![false; gts.len()]; t_count];
    let mut dt_matches = vec![vec![0u64; d_count]; t_count];
    let mut dt_ignore = vec![vec![false; d_count]; t_count];
    if !gts.is_empty() && !dts.is_empty() {
        for (t, &thr) in thresholds.iter().enumerate() {
            for d in 0..d_count {
                let mut best = thr.min(1.0 - 1e-10);
                let mut m: Option<usize> = None;
                for (gi, &g) in gt_order.iter().enumerate() {
                    if gt_matched[t][gi] && !crowd[gi] {
                        continue;
                    }
                    if let Some(mi) = m {
                        if !gt_ignore[mi] && gt_ignore[gi] {
                            break;
                        }
                    }
                    let iou = ious[d][g];
                    if iou < best {
                        continue;
                    }
                    best = iou;
                    m = Some(gi);
                }
                if let Some(mi) = m {
                    dt_ignore[t][d] = gt_ignore[mi];
                    dt_matches[t][d] = gts[gt_order[mi]].ann.id;
                    gt_matched[t][mi] = true;
                }
            }
        }
    }
    for d in 0..d_count {
        let b = &dts[d].bbox;
        let a = b[2] * b[3];
        let out_of_range = a < area.0 || a > area.1;
        for t in 0..t_count {
            if dt_matches[t][d] == 0 && out_of_range {
                dt_ignore[t][d] = true;
            }
        }
    }
    Some(EvalImg {
        dt_scores: dts[..d_count].iter().map(|d| d.score).collect(),
        dt_matches,
        dt_ignore,
        gt_ignore,
    })
}

/// Evaluates `results` against the ground truth `gt` exactly as pycocotools'
/// `COCOeval(gt, dt, "bbox").evaluate(); accumulate(); summarize()` does (see the module docs).
///
/// Errors when a result is for an image not in `gt`, or has a non-finite value or a negative size.
#[expect(
    clippy::too_many_lines,
    reason = "mirrors pycocotools' evaluate/accumulate/summarize line by line, so the two can be compared"
)]
pub fn evaluate(gt: &CocoDataset, results: &[CocoResult]) -> Result<CocoMetrics, VisionError> {
    validate_results(results, gt, Path::new(""))?;
    let thresholds = iou_thresholds();
    let recall_thrs = recall_thresholds();
    let mut img_ids: Vec<u64> = gt.images.iter().map(|i| i.id).collect();
    img_ids.sort_unstable();
    img_ids.dedup();
    let mut cat_ids: Vec<u64> = gt.categories.iter().map(|c| c.id).collect();
    cat_ids.sort_unstable();
    cat_ids.dedup();

    // Group ground truth and results per (image, category), in file order.
    let mut gt_groups: HashMap<(u64, u64), Vec<GtRef<'_>>> = HashMap::new();
    for ann in &gt.annotations {
        gt_groups
            .entry((ann.image_id, ann.category_id))
            .or_default()
            .push(GtRef { ann });
    }
    let mut dt_groups: HashMap<(u64, u64), Vec<&CocoResult>> = HashMap::new();
    for r in results {
        dt_groups
            .entry((r.image_id, r.category_id))
            .or_default()
            .push(r);
    }
    let max_det_last = MAX_DETS[MAX_DETS.len() - 1];
    // Sort detections per group by score (stable), keep maxDets[-1], compute IoUs.
    let mut sorted_dts: HashMap<(u64, u64), Vec<&CocoResult>> = HashMap::new();
    for (key, dts) in &dt_groups {
        let scores: Vec<f64> = dts.iter().map(|d| d.score).collect();
        let order = stable_order_by_score_desc(&scores);
        let kept: Vec<&CocoResult> = order.iter().take(max_det_last).map(|&i| dts[i]).collect();
        sorted_dts.insert(*key, kept);
    }

    let (t_n, r_n, k_n, a_n, m_n) = (
        thresholds.len(),
        recall_thrs.len(),
        cat_ids.len(),
        AREA_RANGES.len(),
        MAX_DETS.len(),
    );
    // precision[t][r][k][a][m], recall[t][k][a][m]
    let p_idx = |t: usize, r: usize, k: usize, a: usize, m: usize| {
        (((t * r_n + r) * k_n + k) * a_n + a) * m_n + m
    };
    let r_idx = |t: usize, k: usize, a: usize, m: usize| ((t * k_n + k) * a_n + a) * m_n + m;
    let mut precision = vec![-1.0f64; t_n * r_n * k_n * a_n * m_n];
    let mut recall = vec![-1.0f64; t_n * k_n * a_n * m_n];

    let empty_gt: Vec<GtRef<'_>> = Vec::new();
    let empty_dt: Vec<&CocoResult> = Vec::new();
    for (k, &cat) in cat_ids.iter().enumerate() {
        // IoUs per image for this category: rows = sorted detections, columns = gt in file order.
        let per_image: Vec<ImageGroup<'_, '_>> = img_ids
            .iter()
            .map(|&img| {
                let g = gt_groups.get(&(img, cat)).unwrap_or(&empty_gt);
                let d = sorted_dts.get(&(img, cat)).unwrap_or(&empty_dt);
                let ious = d
                    .iter()
                    .map(|dt| {
                        g.iter()
                            .map(|gr| coco_iou(&dt.bbox, &gr.ann.bbox, gr.ann.iscrowd != 0))
                            .collect()
                    })
                    .collect();
                (g, d, ious)
            })
            .collect();
        for (a, &area) in AREA_RANGES.iter().enumerate() {
            let evals: Vec<EvalImg> = per_image
                .iter()
                .filter_map(|(g, d, ious)| {
                    evaluate_img(g, d, ious, area, max_det_last, &thresholds)
                })
                .collect();
            if evals.is_empty() {
                continue;
            }
            for (m, &max_det) in MAX_DETS.iter().enumerate() {
                let mut scores = Vec::new();
                let mut matched: Vec<Vec<u64>> = vec![Vec::new(); t_n];
                let mut ignored: Vec<Vec<bool>> = vec![Vec::new(); t_n];
                let mut npig = 0usize;
                for e in &evals {
                    let n = e.dt_scores.len().min(max_det);
                    scores.extend_from_slice(&e.dt_scores[..n]);
                    for t in 0..t_n {
                        matched[t].extend_from_slice(&e.dt_matches[t][..n]);
                        ignored[t].extend_from_slice(&e.dt_ignore[t][..n]);
                    }
                    npig += e.gt_ignore.iter().filter(|&&ig| !ig).count();
                }
                if npig == 0 {
                    continue;
                }
                let order = stable_order_by_score_desc(&scores);
                for t in 0..t_n {
                    let mut tp = 0.0f64;
                    let mut fp = 0.0f64;
                    let mut rc = Vec::with_capacity(order.len());
                    let mut pr = Vec::with_capacity(order.len());
                    for &i in &order {
                        let ig = ignored[t][i];
                        if matched[t][i] != 0 && !ig {
                            tp += 1.0;
                        }
                        if matched[t][i] == 0 && !ig {
                            fp += 1.0;
                        }
                        rc.push(tp / npig as f64);
                        pr.push(tp / (fp + tp + f64::EPSILON));
                    }
                    let nd = rc.len();
                    recall[r_idx(t, k, a, m)] = if nd > 0 { rc[nd - 1] } else { 0.0 };
                    for i in (1..nd).rev() {
                        if pr[i] > pr[i - 1] {
                            pr[i - 1] = pr[i];
                        }
                    }
                    for (ri, &thr) in recall_thrs.iter().enumerate() {
                        // np.searchsorted(rc, thr, side="left"): first index with rc >= thr.
                        let pi = rc.partition_point(|&v| v < thr);
                        precision[p_idx(t, ri, k, a, m)] = if pi < nd { pr[pi] } else { 0.0 };
                    }
                }
            }
        }
    }

    let mean_valid = |values: &mut dyn Iterator<Item = f64>| {
        let (mut sum, mut n) = (0.0, 0usize);
        for v in values {
            if v > -1.0 {
                sum += v;
                n += 1;
            }
        }
        if n == 0 {
            -1.0
        } else {
            sum / n as f64
        }
    };
    let m100 = 2;
    let summarize_ap = |t_sel: Option<usize>, a: usize| {
        let ts: Vec<usize> = match t_sel {
            Some(t) => vec![t],
            None => (0..t_n).collect(),
        };
        let mut it = ts
            .into_iter()
            .flat_map(|t| (0..r_n).flat_map(move |r| (0..k_n).map(move |k| (t, r, k))))
            .map(|(t, r, k)| precision[p_idx(t, r, k, a, m100)]);
        mean_valid(&mut it)
    };
    let summarize_ar = |a: usize, m: usize| {
        let mut it = (0..t_n)
            .flat_map(|t| (0..k_n).map(move |k| (t, k)))
            .map(|(t, k)| recall[r_idx(t, k, a, m)]);
        mean_valid(&mut it)
    };
    Ok(CocoMetrics {
        map: summarize_ap(None, 0),
        map50: summarize_ap(Some(0), 0),
        map75: summarize_ap(Some(5), 0),
        map_small: summarize_ap(None, 1),
        map_medium: summarize_ap(None, 2),
        map_large: summarize_ap(None, 3),
        ar1: summarize_ar(0, 0),
        ar10: summarize_ar(0, 1),
        ar100: summarize_ar(0, 2),
        ar_small: summarize_ar(1, 2),
        ar_medium: summarize_ar(2, 2),
        ar_large: summarize_ar(3, 2),
    })
}

#[cfg(test)]
mod tests {
    use super::super::{parse_results, CocoCategory, CocoImage};
    use super::*;

    fn dataset(anns: &[(u64, u64, [f64; 4])], images: &[u64]) -> CocoDataset {
        CocoDataset {
            images: images
                .iter()
                .map(|&id| CocoImage::new(id, format!("{id}.jpg"), 500, 500))
                .collect(),
            annotations: anns
                .iter()
                .map(|&(id, image_id, bbox)| CocoAnnotation::from_bbox(id, image_id, 1, bbox))
                .collect(),
            categories: vec![CocoCategory {
                id: 1,
                name: "crack".into(),
                supercategory: None,
            }],
            ..CocoDataset::default()
        }
    }

    fn res(image_id: u64, bbox: [f64; 4], score: f64) -> CocoResult {
        CocoResult {
            image_id,
            category_id: 1,
            bbox,
            score,
        }
    }

    #[test]
    fn thresholds_match_numpy() {
        let t = iou_thresholds();
        assert_eq!(t[0], 0.5);
        assert_eq!(t[5], 0.75);
        assert_eq!(t[8], 0.8999999999999999);
        assert_eq!(recall_thresholds()[100], 1.0);
        assert_eq!(recall_thresholds()[3], 0.03);
    }

    #[test]
    fn ground_truth_against_itself_is_perfect() {
        let gt = dataset(
            &[
                (1, 1, [10.0, 10.0, 20.0, 20.0]),
                (2, 1, [100.0, 100.0, 50.0, 60.0]),
                (3, 2, [0.0, 0.0, 200.0, 300.0]),
            ],
            &[1, 2, 3],
        );
        let m = evaluate(&gt, &gt.ground_truth_as_results()).unwrap();
        assert!((m.map - 1.0).abs() < 1e-12, "{}", m.map);
        assert!((m.map50 - 1.0).abs() < 1e-12, "{}", m.map50);
        assert!((m.map_small - 1.0).abs() < 1e-12, "{}", m.map_small);
        assert!((m.map_medium - 1.0).abs() < 1e-12, "{}", m.map_medium);
        assert!((m.map_large - 1.0).abs() < 1e-12, "{}", m.map_large);
        assert!((m.ar1 - 2.0 / 3.0).abs() < 1e-12); // image 1 has two boxes, one detection allowed
        assert!((m.ar100 - 1.0).abs() < 1e-12, "{}", m.ar100);
    }

    #[test]
    fn empty_results_give_zero() {
        let gt = dataset(&[(1, 1, [10.0, 10.0, 20.0, 20.0])], &[1]);
        let m = evaluate(&gt, &[]).unwrap();
        assert_eq!(m.map, 0.0);
        assert_eq!(m.ar100, 0.0);
        assert_eq!(m.map_medium, -1.0); // no medium ground truth
        assert_eq!(m.map_large, -1.0);
    }

    #[test]
    fn hand_computed_case() {
        // Two GT boxes (100×100) on two images. Detections, best first:
        // 0.9 exact on GT 1 (TP at every threshold), 0.8 false positive, 0.7 on GT 2 with IoU 0.6.
        let gt = dataset(
            &[
                (1, 1, [0.0, 0.0, 100.0, 100.0]),
                (2, 2, [0.0, 0.0, 100.0, 100.0]),
            ],
            &[1, 2],
        );
        // IoU of [0,0,100,100] and [0,0,100,75] = 0.75; use [0,0,100,60] → 0.6.
        let r = vec![
            res(1, [0.0, 0.0, 100.0, 100.0], 0.9),
            res(1, [300.0, 300.0, 100.0, 100.0], 0.8),
            res(2, [0.0, 0.0, 100.0, 60.0], 0.7),
        ];
        let m = evaluate(&gt, &r).unwrap();
        // Thresholds ≤ 0.6 (0.5, 0.55, 0.6): TP, FP, TP → precision 1, 1/2, 2/3; envelope 1 up to
        // recall 0.5, 2/3 up to recall 1. AP = (51 * 1 + 50 * 2/3) / 101.
        let ap_hi = (51.0 + 50.0 * 2.0 / 3.0) / 101.0;
        // Thresholds > 0.6: only the first is a TP: recall 0.5, AP = 51 / 101.
        let ap_lo = 51.0 / 101.0;
        assert!((m.map50 - ap_hi).abs() < 1e-12, "{}", m.map50);
        assert!((m.map75 - ap_lo).abs() < 1e-12);
        assert!((m.map - (3.0 * ap_hi + 7.0 * ap_lo) / 10.0).abs() < 1e-12);
        assert!((m.ar100 - (3.0 * 1.0 + 7.0 * 0.5) / 10.0).abs() < 1e-12);
        assert!((m.ar1 - m.ar100).abs() < 1e-12);
        assert_eq!(m.map_small, -1.0);
        assert!((m.map_large - m.map).abs() < 1e-12);
    }

    #[test]
    fn crowd_ground_truth_is_ignored_and_absorbs_detections() {
        let mut gt = dataset(
            &[
                (1, 1, [0.0, 0.0, 100.0, 100.0]),
                (2, 1, [200.0, 200.0, 200.0, 200.0]),
            ],
            &[1],
        );
        gt.annotations[1].iscrowd = 1;
        let r = vec![
            res(1, [0.0, 0.0, 100.0, 100.0], 0.5),
            res(1, [210.0, 210.0, 50.0, 50.0], 0.9),
            res(1, [300.0, 300.0, 50.0, 50.0], 0.8),
        ];
        let m = evaluate(&gt, &r).unwrap();
        assert!((m.map - 1.0).abs() < 1e-12, "{}", m.map);
        assert!((m.ar100 - 1.0).abs() < 1e-12, "{}", m.ar100);
    }

    #[test]
    fn results_are_validated() {
        let gt = dataset(&[(1, 1, [0.0, 0.0, 10.0, 10.0])], &[1]);
        let err = evaluate(&gt, &[res(7, [0.0, 0.0, 1.0, 1.0], 0.5)]).unwrap_err();
        assert!(err.to_string().contains("image id 7"), "{err}");
        assert!(evaluate(&gt, &[res(1, [f64::NAN, 0.0, 1.0, 1.0], 0.5)]).is_err());
        assert!(evaluate(&gt, &[res(1, [0.0, 0.0, 1.0, 1.0], f64::INFINITY)]).is_err());
        assert!(evaluate(&gt, &[res(1, [0.0, 0.0, -1.0, 1.0], 0.5)]).is_err());
        // Parsing results files is crackbot-imaging's (its `results_are_validated` test); the
        // re-export keeps this crate's path working.
        let p = Path::new("dets.json");
        assert!(parse_results("{}", p, &gt).is_err());
    }
}
