//! Perception: a frame from the rig's camera (a camera on hardware, the scene rendered on the
//! simulator), the detector, candidates in surface mm.

use std::path::{Path, PathBuf};

use crackbot_imaging::Homography;
use crackbot_planner::Candidate;
use crackbot_vision::preprocess::PostprocessParams;
use crackbot_vision::{Detection, DetectionSource};
use image::RgbImage;
use serde::{Deserialize, Serialize};

use super::trace::CrackTrace;
use crate::error::io_err;
use crate::inspect::report::{FrameInfo, InspectMode};
use crate::inspect::rig::backend::RigBackend;
use crate::inspect::rig::settings::RigConfig;
use crate::MissionError;

/// What the finger touches of what the camera saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CandidateSource {
    /// Every crack a detection holds, on its centre line (`crackbot_vision::crack_map`, "Where
    /// to touch"): cracks that the detection's dilation joined are touched one by one.
    Cracks,
    /// Every detection once, across the middle of its main axis: fewer strokes, but of cracks
    /// that run close together or cross only one is touched.
    Detections,
}

impl std::str::FromStr for CandidateSource {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cracks" => Ok(CandidateSource::Cracks),
            "detections" => Ok(CandidateSource::Detections),
            _ => Err(format!(
                "unknown candidate source {s:?}: cracks or detections"
            )),
        }
    }
}

/// What the camera proposes and the finger touches: `[perceive]` of the configuration file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerceiveConfig {
    /// The ONNX detector (fused and vision modes; `None`: the committed one).
    #[serde(default)]
    pub detector_model: Option<PathBuf>,
    /// Vision missions: detections below this score are not reported.
    #[serde(serialize_with = "shortest_f32")]
    pub min_score: f32,
    /// Fused missions: detections below this score are not touched. Lower than
    /// [`min_score`](Self::min_score) where wanted: the finger confirms or rejects what the
    /// camera proposes, so a weak detection costs a slide, not a false report.
    #[serde(serialize_with = "shortest_f32")]
    pub proposal_min_score: f32,
    /// What the finger touches (fused) and what is reported (vision).
    pub candidates: CandidateSource,
}

/// A score written as the shortest decimal that reads back as it (0.3, not 0.30000001192092896).
fn shortest_f32<S: serde::Serializer>(v: &f32, s: S) -> Result<S::Ok, S::Error> {
    let shortest: f64 = v.to_string().parse().unwrap_or(f64::from(*v));
    s.serialize_f64(shortest)
}

impl Default for PerceiveConfig {
    fn default() -> Self {
        PerceiveConfig {
            detector_model: None,
            min_score: 0.3,
            proposal_min_score: 0.3,
            candidates: CandidateSource::Cracks,
        }
    }
}

impl PerceiveConfig {
    /// Refuses a setting out of range, naming it.
    pub fn check(&self) -> Result<(), MissionError> {
        for (field, value) in [
            ("perceive.min_score", self.min_score),
            ("perceive.proposal_min_score", self.proposal_min_score),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(MissionError::Setting {
                    field,
                    value: f64::from(value),
                    allowed: "[0, 1]",
                });
            }
        }
        Ok(())
    }

    /// The score under which a detection is left out in `mode`.
    fn min_score(&self, mode: InspectMode) -> f32 {
        match mode {
            InspectMode::Fused => self.proposal_min_score,
            _ => self.min_score,
        }
    }
}

/// What the camera gave: candidates in the scene's frame (rendered or grabbed, detected, mapped
/// to mm) with their detector scores; the detector's crack map seen from the plate, when it
/// predicts one; and the frame itself (saved beside the report).
pub(crate) struct Perceived {
    pub candidates: Vec<(Candidate, f64)>,
    pub trace: Option<CrackTrace>,
    pub frame: FrameInfo,
}

/// Looks at the scene through the camera of `rig` ([`Perceived`]) in a `mode` mission, the
/// frame saved in `out_dir`.
pub(crate) fn perceive(
    (config, mode): (&PerceiveConfig, InspectMode),
    (rig_config, out_dir): (&RigConfig, &Path),
    rig: &mut dyn RigBackend,
) -> Result<Perceived, MissionError> {
    use crackbot_vision::model::{build_detector, DetectorChoice};

    std::fs::create_dir_all(out_dir).map_err(|e| io_err(out_dir, e))?;
    let (image, h) = match &rig_config.camera_calibration {
        Some(path) => through_lens(path, &rig.image(rig_config, mode)?)?,
        None => rig.frame(rig_config, mode)?,
    };
    let frame_path = out_dir.join("frame.png");
    image
        .save(&frame_path)
        .map_err(|source| MissionError::Image {
            path: frame_path.clone(),
            source,
        })?;
    let frame = FrameInfo {
        path: frame_path.display().to_string(),
        width: image.width(),
        height: image.height(),
        surface_to_image: crackbot_imaging::homography::matrix_rows(h.inverse()),
    };
    let choice = DetectorChoice {
        model: config.detector_model.clone(),
        ..DetectorChoice::default()
    };
    let min_score = config.min_score(mode);
    // The detector's own cut must not be above ours. Cracks whose box is small (short, or
    // thin along a pixel axis) are kept where they have a centre line to touch (below).
    let defaults = PostprocessParams::default();
    let post = PostprocessParams {
        score_threshold: defaults.score_threshold.min(min_score),
        min_area_fraction: 0.0,
        ..defaults
    };
    let mut detector = build_detector(&choice, post)?;
    let (detections, map) = detector.detect_with_map(&image)?;
    // Only a fused mission joins what the finger confirmed; a vision report needs no map.
    let trace = map
        .filter(|_| mode == InspectMode::Fused)
        .map(|m| CrackTrace::new(&m, h));
    let area = image.width() as f32 * image.height() as f32;
    let out = candidates(&detections, &h, (config, mode), area);
    Ok(Perceived {
        candidates: out,
        trace,
        frame,
    })
}

/// The frame undistorted by the lens of the calibration file at `path`, and the pixel → plate
/// homography of the undistorted frame (from the file's plate pose). Refuses a frame of another
/// size than the calibration's and a file without the plate's pose.
fn through_lens(path: &Path, image: &RgbImage) -> Result<(RgbImage, Homography), MissionError> {
    use crackbot_calib::{undistort::plate_to_undistorted, CameraFile, FileError};
    let file = CameraFile::load(path)?;
    let pose = file
        .surface_pose()
        .ok_or_else(|| FileError::NoSurface { path: path.into() })?;
    let undistorted = file.undistort(path, image)?;
    let to_plate = plate_to_undistorted(&file.lens(), &pose)
        .try_inverse()
        .ok_or(MissionError::SingularHomography)?;
    let h = Homography::from_nalgebra(to_plate).map_err(|_| MissionError::SingularHomography)?;
    Ok((undistorted, h))
}

/// The candidates of `detections` (image pixels) on the surface (`h`: surface mm → pixels) for
/// a frame of `image_area` pixels, with their detector scores: one per crack piece a detection
/// holds (the crack map's "Where to touch"), else one along its axis or over its box. Detections
/// under the mission's score, the box head's, and small boxes without a centre line are left out.
fn candidates(
    detections: &[Detection],
    h: &Homography,
    (config, mode): (&PerceiveConfig, InspectMode),
    image_area: f32,
) -> Vec<(Candidate, f64)> {
    let min_score = config.min_score(mode);
    let min_area = PostprocessParams::default().min_area_fraction * image_area;
    let mut out = Vec::new();
    let mut id = 0u64;
    for d in detections {
        // The box head's boxes (boxes in the crack photos' convention, no centre line) were
        // never checked on the rendered scenes: the robot touches the crack map's cracks only.
        if d.score < min_score || d.source == DetectionSource::BoxHead {
            continue;
        }
        let to_mm = |p: [f32; 2]| h.pixel_to_surface([f64::from(p[0]), f64::from(p[1])]).ok();
        let score = f64::from(d.score);
        // One candidate per crack the detection holds, touched on its centre line
        // (`crackbot_vision::crack_map`, "Where to touch"): the dilation that joins a broken
        // crack also joins cracks that run close together or cross.
        let pieces = d
            .shape
            .as_ref()
            .filter(|s| config.candidates == CandidateSource::Cracks && !s.pieces.is_empty());
        // Under the datasets' box area, only a crack with a centre line of its own is kept.
        let small = d.bbox.area() < min_area;
        if small && pieces.is_none() {
            continue;
        }
        if let Some(shape) = pieces {
            for piece in &shape.pieces {
                if let (Some(a), Some(b)) = (to_mm(piece.axis[0]), to_mm(piece.axis[1])) {
                    id += 1;
                    // Its width at the touch, by the axis's scale there (mm per pixel), so a
                    // wide crack gets a stroke that starts and ends on sound surface.
                    let mm_per_px =
                        (b[0] - a[0]).hypot(b[1] - a[1]) / f64::from(piece.length_px.max(1.0));
                    let width = f64::from(piece.width_px) * mm_per_px;
                    let c = Candidate::from_axis(id, [a, b], Some(width), score);
                    out.push((c, score));
                }
            }
            continue;
        }
        id += 1;
        let c = match &d.shape {
            Some(shape) => match (to_mm(shape.axis[0]), to_mm(shape.axis[1])) {
                (Some(a), Some(b)) => Candidate::from_axis(id, [a, b], None, score),
                _ => continue,
            },
            None => {
                let b = &d.bbox;
                match (to_mm([b.x0, b.y0]), to_mm([b.x1, b.y1])) {
                    (Some(a), Some(c)) => Candidate::from_box(
                        id,
                        [a[0].min(c[0]), a[1].min(c[1])],
                        [a[0].max(c[0]), a[1].max(c[1])],
                        score,
                    ),
                    _ => continue,
                }
            }
        };
        out.push((c, score));
    }
    out
}

#[cfg(all(test, feature = "sim"))]
mod tests {
    use super::*;
    use crate::inspect::rig::simulated::SimulatedRig;
    use crate::inspect::rig::site::Site;
    use crackbot_sim::random_scene::{as_printed, trial_params};
    use crackbot_sim::surface::distance_to_polyline;

    #[test]
    fn a_short_crack_along_a_pixel_row_and_one_meeting_another_in_a_v_get_candidates() {
        // Trial scene 6098: a crack 16 mm long running along the frame's rows, whose box is
        // under the crack datasets' 0.1 % of the image. Trial scene 6011: a 31 mm crack that
        // meets a longer one at a corner, thinned to one bent centre line with it. Trial scene
        // 10217: a 0.6 mm crack running diagonally across the map's cells, two cells thick,
        // whose centre line the thinning used to eat whole, ending in a V with another crack.
        for (seed, nth) in [(6098, 1), (6011, 0), (10217, 0)] {
            let scene = as_printed(&crackbot_sim::random_scene(&trial_params(), seed).unwrap());
            let crack = scene
                .features
                .iter()
                .filter_map(|f| match f {
                    crackbot_sim::Feature::Crack { path, .. } => Some(path.clone()),
                    _ => None,
                })
                .nth(nth)
                .unwrap();
            let dir = tempfile::tempdir().unwrap();
            let mut rig = RigConfig::at(Site::default());
            rig.set_scene(scene);
            let c = PerceiveConfig::default();
            let seen = perceive(
                (&c, InspectMode::Fused),
                (&rig, dir.path()),
                &mut SimulatedRig::default(),
            )
            .unwrap();
            let near: Vec<f64> = seen
                .candidates
                .iter()
                .map(|(c, _)| distance_to_polyline(&crack, c.centre_mm))
                .collect();
            assert!(
                near.iter().any(|&d| d < 3.0),
                "seed {seed}: candidates' distances from the crack {near:?}"
            );
        }
    }

    #[test]
    fn the_box_heads_boxes_never_become_candidates() {
        use crackbot_vision::{BoundingBox, Detection, DetectionSource};
        let config = PerceiveConfig::default();
        // 0.1 mm per pixel.
        let h =
            Homography::from_matrix([[0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 1.0]]).unwrap();
        let boxed = Detection::boxed(BoundingBox::from_xywh(100.0, 100.0, 80.0, 60.0), 0.45);
        let head = Detection {
            source: DetectionSource::BoxHead,
            ..boxed.clone()
        };
        for mode in [InspectMode::Fused, InspectMode::Vision] {
            let area = 640.0 * 480.0;
            // A box detector's box is a candidate over its box, the head's is not.
            let got = candidates(&[boxed.clone(), head.clone()], &h, (&config, mode), area);
            assert_eq!(got.len(), 1, "{mode:?}");
            assert!(
                (got[0].0.centre_mm[0] - 14.0).abs() < 1e-6,
                "{:?}",
                got[0].0
            );
            assert!(candidates(std::slice::from_ref(&head), &h, (&config, mode), area).is_empty());
        }
    }
}
