//! Combining the detections of several frames of one view (camera and scene still) into one list,
//! so that a crack seen in most frames is kept and a one-frame flicker is dropped.
//!
//! Conventions:
//! * Greedy clustering across frames: all detections, best score first (ties: earlier frame, then
//!   earlier in the frame), each joins the cluster whose *seed* (its first, best member) has the
//!   highest IoU ≥ [`FusionParams::iou`] with it among the clusters that have no member from its
//!   frame yet; otherwise it seeds a new cluster. So a cluster has at most one member per frame.
//! * Fused box: the score-weighted mean of the members' corners (plain mean if all scores are 0).
//! * Fused score: the sum of the members' scores divided by the number of frames — a crack seen in
//!   every frame keeps its score; one seen in 1 of 5 frames gets a fifth of it.
//! * Detections with a non-finite box or score, or a negative score, are dropped before clustering.

use serde::{Deserialize, Serialize};

use crate::{BoundingBox, Detection, DetectionSource, VisionError};

/// Parameters of [`fuse`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct FusionParams {
    /// IoU with a cluster's seed needed to join it (default 0.5).
    pub iou: f32,
    /// A fused detection must be seen in at least this many frames (default 1).
    pub min_frames: usize,
}

impl Default for FusionParams {
    fn default() -> Self {
        Self {
            iou: 0.5,
            min_frames: 1,
        }
    }
}

impl FusionParams {
    /// Checks `iou` is in `[0, 1]`.
    pub fn validate(&self) -> Result<(), VisionError> {
        if !(0.0..=1.0).contains(&self.iou) {
            return Err(VisionError::setting(
                "fusion iou",
                f64::from(self.iou),
                "in [0, 1]",
            ));
        }
        Ok(())
    }
}

/// One detection fused over frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FusedDetection {
    /// Fused box and score (see the module docs).
    pub detection: Detection,
    /// In how many frames it was seen.
    pub frames_seen: usize,
    /// `(frame index, index in that frame)` of each member, best score first.
    pub members: Vec<(usize, usize)>,
}

struct Cluster {
    seed: BoundingBox,
    frames: Vec<bool>,
    members: Vec<(usize, usize, Detection)>,
}

/// Fuses the detections of `frames` (see the module docs), sorted by fused score, best first
/// (ties: more frames first). Parameters are not validated here (see [`FusionParams::validate`]):
/// an `iou` above 1 or NaN lets nothing join, one ≤ 0 lets anything join.
pub fn fuse(frames: &[Vec<Detection>], params: &FusionParams) -> Vec<FusedDetection> {
    let n_frames = frames.len();
    if n_frames == 0 {
        return Vec::new();
    }
    let mut all: Vec<(usize, usize, Detection)> = frames
        .iter()
        .enumerate()
        .flat_map(|(f, dets)| dets.iter().enumerate().map(move |(i, d)| (f, i, d.clone())))
        .filter(|(_, _, d)| d.bbox.is_finite() && d.score.is_finite() && d.score >= 0.0)
        .collect();
    // Stable: ties keep frame order, then order within the frame.
    all.sort_by(|a, b| b.2.score.total_cmp(&a.2.score));
    let mut clusters: Vec<Cluster> = Vec::new();
    for (f, i, d) in all {
        let mut best: Option<(usize, f32)> = None;
        for (c, cluster) in clusters.iter().enumerate() {
            if cluster.frames[f] {
                continue;
            }
            let iou = cluster.seed.iou(&d.bbox);
            if iou >= params.iou && best.is_none_or(|(_, b)| iou > b) {
                best = Some((c, iou));
            }
        }
        match best {
            Some((c, _)) => {
                clusters[c].frames[f] = true;
                clusters[c].members.push((f, i, d));
            }
            None => {
                let mut frames_mask = vec![false; n_frames];
                frames_mask[f] = true;
                clusters.push(Cluster {
                    seed: d.bbox,
                    frames: frames_mask,
                    members: vec![(f, i, d)],
                });
            }
        }
    }
    let mut fused: Vec<FusedDetection> = clusters
        .into_iter()
        .filter(|c| c.members.len() >= params.min_frames)
        .map(|c| {
            let total: f64 = c.members.iter().map(|(_, _, d)| f64::from(d.score)).sum();
            let weights: Vec<f64> = if total > 0.0 {
                c.members
                    .iter()
                    .map(|(_, _, d)| f64::from(d.score) / total)
                    .collect()
            } else {
                vec![1.0 / c.members.len() as f64; c.members.len()]
            };
            let mean = |get: fn(&BoundingBox) -> f32| {
                c.members
                    .iter()
                    .zip(&weights)
                    .map(|((_, _, d), w)| f64::from(get(&d.bbox)) * w)
                    .sum::<f64>() as f32
            };
            // The member the fused score trusts most.
            let best = c
                .members
                .iter()
                .max_by(|a, b| a.2.score.total_cmp(&b.2.score));
            FusedDetection {
                detection: Detection {
                    bbox: BoundingBox {
                        x0: mean(|b| b.x0),
                        y0: mean(|b| b.y0),
                        x1: mean(|b| b.x1),
                        y1: mean(|b| b.y1),
                    },
                    score: (total / n_frames as f64) as f32,
                    shape: best.and_then(|(_, _, d)| d.shape.clone()),
                    source: best.map_or(DetectionSource::Primary, |(_, _, d)| d.source),
                },
                frames_seen: c.members.len(),
                members: c.members.iter().map(|&(f, i, _)| (f, i)).collect(),
            }
        })
        .collect();
    fused.sort_by(|a, b| {
        b.detection
            .score
            .total_cmp(&a.detection.score)
            .then(b.frames_seen.cmp(&a.frames_seen))
    });
    fused
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boxes::det;

    #[test]
    fn a_crack_missing_in_one_of_five_frames_is_still_reported() {
        let mut frames: Vec<Vec<Detection>> = (0..5)
            .map(|k| vec![det(10.0 + k as f32, 20.0, 110.0 + k as f32, 40.0, 0.8)])
            .collect();
        frames[3].clear();
        let fused = fuse(
            &frames,
            &FusionParams {
                iou: 0.5,
                min_frames: 3,
            },
        );
        assert_eq!(fused.len(), 1);
        assert_eq!(fused[0].frames_seen, 4);
        assert!((fused[0].detection.score - 0.8 * 4.0 / 5.0).abs() < 1e-6);
        // Equal scores: the plain mean of x0 = 10, 11, 12, 14.
        assert!((fused[0].detection.bbox.x0 - 11.75).abs() < 1e-5);
        assert_eq!(fused[0].members, vec![(0, 0), (1, 0), (2, 0), (4, 0)]);
    }

    #[test]
    fn a_crack_seen_in_every_frame_keeps_its_score_and_boxes_are_score_weighted() {
        let frames = vec![
            vec![det(0.0, 0.0, 100.0, 10.0, 0.9)],
            vec![det(10.0, 0.0, 110.0, 10.0, 0.3)],
            vec![det(0.0, 0.0, 100.0, 10.0, 0.6)],
        ];
        let fused = fuse(&frames, &FusionParams::default());
        assert_eq!(fused.len(), 1);
        assert!((fused[0].detection.score - 0.6).abs() < 1e-6);
        assert!((fused[0].detection.bbox.x0 - 10.0 * 0.3 / 1.8).abs() < 1e-5);
    }

    #[test]
    fn one_frame_false_positive_is_suppressed_with_min_frames_2() {
        let crack = det(50.0, 50.0, 150.0, 70.0, 0.7);
        let mut frames = vec![vec![crack]; 5];
        frames[2].push(det(300.0, 300.0, 340.0, 320.0, 0.95));
        let all = fuse(
            &frames,
            &FusionParams {
                iou: 0.5,
                min_frames: 1,
            },
        );
        assert_eq!(all.len(), 2);
        // The flicker had the best single-frame score but is seen once: a fifth of 0.95.
        assert!((all[1].detection.score - 0.19).abs() < 1e-6);
        assert!((all[0].detection.score - 0.7).abs() < 1e-6);
        let fused = fuse(
            &frames,
            &FusionParams {
                iou: 0.5,
                min_frames: 2,
            },
        );
        assert_eq!(fused.len(), 1);
        assert_eq!(fused[0].frames_seen, 5);
    }

    #[test]
    fn at_most_one_member_per_frame() {
        // Two overlapping detections in one frame stay in different clusters.
        let frames = vec![
            vec![
                det(0.0, 0.0, 10.0, 10.0, 0.9),
                det(0.0, 0.0, 10.0, 11.0, 0.8),
            ],
            vec![det(0.0, 0.0, 10.0, 10.0, 0.85)],
        ];
        let fused = fuse(&frames, &FusionParams::default());
        assert_eq!(fused.len(), 2);
        assert_eq!(fused[0].frames_seen, 2);
        assert_eq!(fused[0].members, vec![(0, 0), (1, 0)]);
        assert_eq!(fused[1].frames_seen, 1);
        assert!(fused.iter().all(|f| {
            let mut fr: Vec<usize> = f.members.iter().map(|m| m.0).collect();
            fr.dedup();
            fr.len() == f.members.len()
        }));
    }

    #[test]
    fn empty_input() {
        assert!(fuse(&[], &FusionParams::default()).is_empty());
        assert!(fuse(&[vec![], vec![]], &FusionParams::default()).is_empty());
    }

    #[test]
    fn non_finite_scores_and_boxes_are_dropped() {
        let frames = vec![
            vec![
                det(f32::NAN, 0.0, 10.0, 10.0, 0.9),
                det(0.0, 0.0, 10.0, 10.0, f32::NAN),
                det(0.0, 0.0, f32::INFINITY, 10.0, 0.9),
                det(0.0, 0.0, 10.0, 10.0, -0.5),
                det(0.0, 0.0, 10.0, 10.0, 0.5),
            ],
            vec![det(0.0, 0.0, 10.0, 10.0, f32::INFINITY)],
        ];
        let fused = fuse(&frames, &FusionParams::default());
        assert_eq!(fused.len(), 1);
        assert_eq!(fused[0].members, vec![(0, 4)]);
        assert!(fused[0].detection.bbox.is_finite() && fused[0].detection.score.is_finite());
    }

    #[test]
    fn invalid_parameters_and_zero_scores() {
        assert!(FusionParams {
            iou: f32::NAN,
            min_frames: 1
        }
        .validate()
        .is_err());
        assert!(FusionParams {
            iou: 1.5,
            min_frames: 1
        }
        .validate()
        .is_err());
        assert!(FusionParams::default().validate().is_ok());
        // NaN IoU: nothing joins.
        let two = vec![
            vec![det(0.0, 0.0, 10.0, 10.0, 0.5)],
            vec![det(0.0, 0.0, 10.0, 10.0, 0.5)],
        ];
        assert_eq!(
            fuse(
                &two,
                &FusionParams {
                    iou: f32::NAN,
                    min_frames: 1
                }
            )
            .len(),
            2
        );
        let frames = vec![
            vec![det(0.0, 0.0, 10.0, 10.0, 0.0)],
            vec![det(2.0, 0.0, 12.0, 10.0, 0.0)],
        ];
        let fused = fuse(
            &frames,
            &FusionParams {
                iou: 0.5,
                min_frames: 2,
            },
        );
        assert_eq!(fused.len(), 1);
        assert_eq!(fused[0].detection.bbox.x0, 1.0);
        assert_eq!(fused[0].detection.score, 0.0);
    }
}
