//! Perception: a frame (rendered, or a camera file), the detector, candidates in surface mm.

use super::*;

/// What the camera gave: candidates in the scene's frame (rendered or grabbed, detected, mapped
/// to mm) with their detector scores; the detector's crack map seen from the plate, when it
/// predicts one; and the frame itself (saved beside the report).
pub(super) struct Perceived {
    pub candidates: Vec<(Candidate, f64)>,
    pub trace: Option<CrackTrace>,
    pub frame: FrameInfo,
}

/// Looks at the scene ([`Perceived`]).
pub(super) fn perceive(config: &InspectConfig) -> Result<Perceived, MissionError> {
    use crackbot_sim::render::{render, CrackAssets, RenderOptions};
    use crackbot_vision::model::{build_detector, DetectorChoice};
    use crackbot_vision::preprocess::PostprocessParams;

    std::fs::create_dir_all(&config.out_dir).map_err(|e| io_err(&config.out_dir, e))?;
    let (image, h) = match &config.hardware {
        Some(hw) => {
            let camera = hw.camera.as_ref().ok_or_else(|| {
                MissionError::Invalid(format!(
                    "a {:?} mission needs a camera (--camera DEVICE|FILE|URL)",
                    config.mode
                ))
            })?;
            let cal = hw.homography.as_ref().ok_or_else(|| {
                MissionError::Invalid(
                    "a camera frame needs its pixel → surface calibration (--homography FILE, from `crackbot homography fit`)".into(),
                )
            })?;
            use crackbot_vision::camera::{grab_frame, CameraSource, DEFAULT_TIMEOUT};
            let source = CameraSource::parse(&camera.to_string_lossy());
            let image = grab_frame(&source, None, DEFAULT_TIMEOUT)
                .map_err(|e| MissionError::Invalid(format!("camera {e}")))?;
            let h = crackbot_vision::homography::HomographyCalibration::load(cal)?.homography()?;
            (image, h)
        }
        None => {
            let assets = CrackAssets::load_default()?;
            let frame = render(
                &config.scene,
                &assets,
                &RenderOptions::default(),
                config.seed,
            )?;
            let h = crackbot_imaging::Homography::from_nalgebra(
                frame.plate_to_image.try_inverse().ok_or_else(|| {
                    MissionError::Invalid("the camera's homography is singular".into())
                })?,
            )
            .map_err(|e| MissionError::Invalid(e.to_string()))?;
            (frame.image, h)
        }
    };
    let frame_path = config.out_dir.join("frame.png");
    image
        .save(&frame_path)
        .map_err(|e| MissionError::Invalid(format!("{}: {e}", frame_path.display())))?;
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
    let min_score = match config.mode {
        InspectMode::Fused => config.proposal_min_score,
        _ => config.min_score,
    };
    // The detector's own cut must not be above ours.
    let post = PostprocessParams {
        score_threshold: PostprocessParams::default().score_threshold.min(min_score),
        ..PostprocessParams::default()
    };
    let mut detector = build_detector(&choice, post)?;
    let (detections, map) = detector.detect_with_map(&image)?;
    // Only a fused mission joins what the finger confirmed; a vision report needs no map.
    let trace = map
        .filter(|_| config.mode == InspectMode::Fused)
        .map(|m| CrackTrace::new(&m, h));
    let mut out = Vec::new();
    let mut id = 0u64;
    for d in &detections {
        if d.score < min_score {
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
    Ok(Perceived {
        candidates: out,
        trace,
        frame,
    })
}

pub(super) fn io_err(path: &Path, e: std::io::Error) -> MissionError {
    MissionError::Invalid(format!("{}: {e}", path.display()))
}
