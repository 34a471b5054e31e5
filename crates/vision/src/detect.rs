//! The `crackbot detect` flow: a detector over images, detections above a threshold, their
//! centres on the surface through a homography, fusion over the frames of one view, and the
//! boxes drawn into copies of the images.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::fusion::{fuse, FusionParams};
use crate::homography::Homography;
use crate::{Detection, Detector, VisionError};

/// Colour of a frame's own detections in annotated images.
pub const DETECTION_COLOUR: [u8; 3] = [255, 40, 40];
/// Colour of the fused detections in annotated images.
pub const FUSED_COLOUR: [u8; 3] = [40, 220, 255];
/// Colour of the box head's boxes in annotated images (`crackbot detect --box-head`).
pub const BOX_HEAD_COLOUR: [u8; 3] = [255, 150, 40];

/// What to do with the images.
#[derive(Debug, Clone, Default)]
pub struct DetectConfig {
    /// Minimum score of a reported crack, in `[0, 1]`.
    pub threshold: f32,
    /// Pixel → surface homography: adds each detection's centre in mm.
    pub homography: Option<Homography>,
    /// Treat the images as frames of one view and fuse their detections.
    pub fuse: Option<FusionParams>,
    /// Write `<image stem>-detections.png` with the boxes drawn into this folder.
    pub annotate: Option<PathBuf>,
}

/// One detection in a [`DetectReport`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DetectionReport {
    /// `[x0, y0, x1, y1]` in pixels.
    pub bbox: [f32; 4],
    /// Confidence.
    pub score: f32,
    /// The box centre on the surface, mm (with a homography, where the centre maps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub centre_mm: Option<[f64; 2]>,
    /// Frames the detection was seen in (fused detections only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames_seen: Option<usize>,
    /// `"box_head"` for the model's box head (a box only, scored under 0.5); absent for the
    /// detector's own detections ([`crate::DetectionSource`]).
    #[serde(skip_serializing_if = "crate::DetectionSource::is_primary")]
    pub source: crate::DetectionSource,
    /// The crack's main axis, its two ends in pixels (detectors with a crack map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis_px: Option<[[f32; 2]; 2]>,
    /// The crack's centre line in pixels, end to end (detectors with a crack map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polyline_px: Option<Vec<[f32; 2]>>,
    /// The main axis on the surface, mm (with a homography that maps both ends).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis_mm: Option<[[f64; 2]; 2]>,
    /// The centre line on the surface, mm (with a homography that maps every point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polyline_mm: Option<Vec<[f64; 2]>>,
    /// Length of the centre line on the surface, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_mm: Option<f64>,
    /// The cracks the detection holds and where to touch each, pixels
    /// ([`crate::crack_map::CrackShape::pieces`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pieces_px: Vec<crate::crack_map::CrackPiece>,
    /// Each piece's touch point on the surface, mm (with a homography that maps them all).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub touch_mm: Option<Vec<[f64; 2]>>,
}

/// One image of a [`DetectReport`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageReport {
    /// The image file.
    pub file: String,
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Milliseconds of the `detect` call.
    pub ms: f64,
    /// Detections at or above the threshold, best first.
    pub detections: Vec<DetectionReport>,
}

/// What `crackbot detect` reports (its `--json` object).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DetectReport {
    /// The detector's name.
    pub detector: String,
    /// The score threshold.
    pub threshold: f32,
    /// Per image.
    pub images: Vec<ImageReport>,
    /// The fused detections (with fusion).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fused: Option<Vec<DetectionReport>>,
    /// The annotated images written.
    #[serde(skip)]
    pub annotated: Vec<PathBuf>,
}

fn read_rgb(path: &Path) -> Result<image::RgbImage, VisionError> {
    Ok(image::open(path)
        .map_err(|e| VisionError::Image {
            path: path.to_path_buf(),
            message: format!("cannot read the image: {e}"),
        })?
        .to_rgb8())
}

/// Runs `detector` over `images` as `config` says. Errors on a threshold outside `[0, 1]`,
/// invalid fusion parameters, an image that cannot be read, a failed detection, or an annotated
/// image that cannot be written, naming the file.
pub fn detect_images(
    detector: &mut dyn Detector,
    images: &[PathBuf],
    config: &DetectConfig,
) -> Result<DetectReport, VisionError> {
    if !(0.0..=1.0).contains(&config.threshold) {
        return Err(VisionError::setting(
            "threshold",
            f64::from(config.threshold),
            "in [0, 1]",
        ));
    }
    if let Some(p) = &config.fuse {
        p.validate()?;
    }
    let mut frames = Vec::with_capacity(images.len());
    for path in images {
        let rgb = read_rgb(path)?;
        let started = Instant::now();
        let mut found = detector.detect(&rgb).map_err(|e| VisionError::Image {
            path: path.clone(),
            message: format!("detecting: {e}"),
        })?;
        let ms = started.elapsed().as_secs_f64() * 1e3;
        found.retain(|d| d.score >= config.threshold);
        frames.push((path, rgb, found, ms));
    }
    // A centre the homography cannot map (behind the camera's horizon) has no surface position.
    let to_mm = |d: &Detection| -> Option<[f64; 2]> {
        let (cx, cy) = d.bbox.centre();
        config
            .homography
            .as_ref()
            .and_then(|h| h.pixel_to_surface([f64::from(cx), f64::from(cy)]).ok())
    };
    // Points of the crack's course on the surface: all of them, or none.
    let points_mm = |pts: &[[f32; 2]]| -> Option<Vec<[f64; 2]>> {
        let h = config.homography.as_ref()?;
        pts.iter()
            .map(|p| h.pixel_to_surface([f64::from(p[0]), f64::from(p[1])]).ok())
            .collect()
    };
    let report_of = |d: &Detection, frames_seen: Option<usize>| {
        let shape = d.shape.as_ref();
        let polyline_mm = shape.and_then(|s| points_mm(&s.polyline));
        DetectionReport {
            bbox: [d.bbox.x0, d.bbox.y0, d.bbox.x1, d.bbox.y1],
            score: d.score,
            centre_mm: to_mm(d),
            frames_seen,
            source: d.source,
            axis_px: shape.map(|s| s.axis),
            polyline_px: shape.map(|s| s.polyline.clone()),
            axis_mm: shape.and_then(|s| points_mm(&s.axis)).map(|a| [a[0], a[1]]),
            length_mm: polyline_mm.as_ref().map(|p| {
                p.windows(2)
                    .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
                    .sum()
            }),
            polyline_mm,
            pieces_px: shape.map(|s| s.pieces.clone()).unwrap_or_default(),
            touch_mm: shape
                .filter(|s| !s.pieces.is_empty())
                .and_then(|s| points_mm(&s.pieces.iter().map(|p| p.touch).collect::<Vec<_>>())),
        }
    };
    let fused = config.fuse.as_ref().map(|params| {
        let dets: Vec<Vec<Detection>> = frames.iter().map(|f| f.2.clone()).collect();
        fuse(&dets, params)
    });
    let mut annotated = Vec::new();
    if let Some(dir) = &config.annotate {
        std::fs::create_dir_all(dir).map_err(VisionError::io(dir))?;
        for (path, rgb, found, _) in &frames {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
            let out = dir.join(format!("{stem}-detections.png"));
            let mut canvas = rgb.clone();
            for d in found {
                draw_box(&mut canvas, d, detection_colour(d));
            }
            for f in fused.iter().flatten() {
                draw_box(&mut canvas, &f.detection, FUSED_COLOUR);
            }
            canvas.save(&out).map_err(|e| VisionError::Image {
                path: out.clone(),
                message: e.to_string(),
            })?;
            annotated.push(out);
        }
    }
    Ok(DetectReport {
        detector: detector.name(),
        threshold: config.threshold,
        images: frames
            .iter()
            .map(|(path, rgb, found, ms)| ImageReport {
                file: path.display().to_string(),
                width: rgb.width(),
                height: rgb.height(),
                ms: *ms,
                detections: found.iter().map(|d| report_of(d, None)).collect(),
            })
            .collect(),
        fused: fused.as_ref().map(|fused| {
            fused
                .iter()
                .map(|f| report_of(&f.detection, Some(f.frames_seen)))
                .collect()
        }),
        annotated,
    })
}

/// The colour a detection is drawn in: [`DETECTION_COLOUR`], or [`BOX_HEAD_COLOUR`] for the
/// box head's boxes.
pub fn detection_colour(d: &Detection) -> [u8; 3] {
    match d.source {
        crate::DetectionSource::Primary => DETECTION_COLOUR,
        crate::DetectionSource::BoxHead => BOX_HEAD_COLOUR,
    }
}

/// Draws a 3-pixel rectangle outline of `d`'s box (clipped to the image), and the crack's
/// centre line where the detector gives one.
pub fn draw_box(img: &mut image::RgbImage, d: &Detection, colour: [u8; 3]) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    if w == 0 || h == 0 || !d.bbox.is_finite() {
        return;
    }
    let clamp = |v: f32, hi: i64| (v.round() as i64).clamp(0, hi - 1);
    let (x0, x1) = (clamp(d.bbox.x0, w), clamp(d.bbox.x1, w));
    let (y0, y1) = (clamp(d.bbox.y0, h), clamp(d.bbox.y1, h));
    for t in 0..3 {
        for x in x0..=x1 {
            for y in [y0 + t, y1 - t] {
                if (0..h).contains(&y) {
                    img.put_pixel(x as u32, y as u32, image::Rgb(colour));
                }
            }
        }
        for y in y0..=y1 {
            for x in [x0 + t, x1 - t] {
                if (0..w).contains(&x) {
                    img.put_pixel(x as u32, y as u32, image::Rgb(colour));
                }
            }
        }
    }
    draw_course(img, d);
}

/// Colour of a crack's centre line in annotated images.
pub const COURSE_COLOUR: [u8; 3] = [255, 230, 0];

/// Colour of the touch points and the strokes across them in annotated images.
pub const TOUCH_COLOUR: [u8; 3] = [255, 0, 200];

/// Draws the crack's centre line of `d` (one pixel wide), where the detector gives one, and for
/// each crack it holds ([`crate::crack_map::CrackPiece`]) a stroke across it through its touch
/// point.
fn draw_course(img: &mut image::RgbImage, d: &Detection) {
    if let Some(shape) = &d.shape {
        for seg in shape.polyline.windows(2) {
            draw_line(img, seg[0], seg[1], COURSE_COLOUR);
        }
        for piece in &shape.pieces {
            let [a, b] = piece.axis;
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l = dx.hypot(dy);
            if l.is_nan() || l <= 0.0 {
                continue;
            }
            // Across the piece: its width and 8 px of sound surface on each side.
            let half = piece.width_px / 2.0 + 8.0;
            let (nx, ny) = (-dy / l * half, dx / l * half);
            let t = piece.touch;
            for o in [-1.0, 0.0, 1.0] {
                // Three pixels wide: offsets along the piece.
                let (ox, oy) = (dx / l * o, dy / l * o);
                draw_line(
                    img,
                    [t[0] - nx + ox, t[1] - ny + oy],
                    [t[0] + nx + ox, t[1] + ny + oy],
                    TOUCH_COLOUR,
                );
            }
        }
    }
}

/// A one-pixel line from `a` to `b` (image pixels), clipped to the image.
fn draw_line(img: &mut image::RgbImage, a: [f32; 2], b: [f32; 2], colour: [u8; 3]) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let steps = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).max(1);
    if steps > 100_000 {
        return;
    }
    for k in 0..=steps {
        let t = k as f32 / steps as f32;
        let (x, y) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        let (x, y) = (x.round() as i64, y.round() as i64);
        if (0..w).contains(&x) && (0..h).contains(&y) {
            img.put_pixel(x as u32, y as u32, image::Rgb(colour));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Two;
    impl Detector for Two {
        fn name(&self) -> String {
            "two".into()
        }
        fn detect(&mut self, _image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
            Ok(vec![
                Detection {
                    bbox: crate::BoundingBox::from_xywh(2.0, 2.0, 4.0, 4.0),
                    score: 0.8,
                    shape: None,
                    source: crate::DetectionSource::Primary,
                },
                Detection {
                    bbox: crate::BoundingBox::from_xywh(10.0, 1.0, 3.0, 3.0),
                    score: 0.1,
                    shape: None,
                    source: crate::DetectionSource::Primary,
                },
            ])
        }
    }

    /// One crack with its centre line, from (2, 2) over (6, 2) to (6, 6), and a piece touched at
    /// (24, 12) running along y.
    struct Shaped;
    impl Detector for Shaped {
        fn name(&self) -> String {
            "shaped".into()
        }
        fn detect(&mut self, _image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
            Ok(vec![Detection {
                bbox: crate::BoundingBox::from_xywh(2.0, 2.0, 4.0, 4.0),
                score: 0.9,
                shape: Some(crate::crack_map::CrackShape {
                    axis: [[2.0, 2.0], [6.0, 6.0]],
                    polyline: vec![[2.0, 2.0], [6.0, 2.0], [6.0, 6.0]],
                    length_px: 8.0,
                    pieces: vec![crate::crack_map::CrackPiece {
                        touch: [24.0, 12.0],
                        axis: [[24.0, 9.0], [24.0, 15.0]],
                        length_px: 6.0,
                        width_px: 2.0,
                    }],
                }),
                source: crate::DetectionSource::Primary,
            }])
        }
    }

    #[test]
    fn the_crack_course_is_reported_in_pixels_and_millimetres_and_drawn() {
        let dir = tempfile::tempdir().unwrap();
        let img = dir.path().join("f.png");
        image::RgbImage::new(40, 16).save(&img).unwrap();
        let config = DetectConfig {
            threshold: 0.5,
            homography: Some(
                Homography::from_matrix([[0.5, 0.0, 1.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]])
                    .unwrap(),
            ),
            fuse: None,
            annotate: Some(dir.path().join("out")),
        };
        let r = detect_images(&mut Shaped, &[img], &config).unwrap();
        let d = &r.images[0].detections[0];
        assert_eq!(d.polyline_px.as_ref().unwrap().len(), 3);
        assert_eq!(d.axis_px, Some([[2.0, 2.0], [6.0, 6.0]]));
        let mm = d.polyline_mm.as_ref().unwrap();
        for (got, want) in mm.iter().zip([[2.0, 1.0], [4.0, 1.0], [4.0, 3.0]]) {
            assert!(
                (got[0] - want[0]).abs() < 1e-9 && (got[1] - want[1]).abs() < 1e-9,
                "{mm:?}"
            );
        }
        assert!((d.length_mm.unwrap() - 4.0).abs() < 1e-9);
        assert!(d.axis_mm.is_some());
        let drawn = image::open(&r.annotated[0]).unwrap().to_rgb8();
        assert_eq!(drawn.get_pixel(4, 2).0, COURSE_COLOUR);
        assert_eq!(drawn.get_pixel(6, 4).0, COURSE_COLOUR);
        assert_eq!(drawn.get_pixel(4, 4).0, DETECTION_COLOUR);
        // The piece: reported with its touch point in mm, and a stroke drawn across it (its
        // width and 8 px on each side).
        assert_eq!(d.pieces_px.len(), 1);
        assert_eq!(d.touch_mm, Some(vec![[13.0, 6.0]]));
        for x in [16, 24, 32] {
            assert_eq!(drawn.get_pixel(x, 12).0, TOUCH_COLOUR, "x = {x}");
        }
        assert_ne!(drawn.get_pixel(24, 8).0, TOUCH_COLOUR);
        // Without a homography: pixels only.
        let r = detect_images(
            &mut Shaped,
            &[dir.path().join("f.png")],
            &DetectConfig {
                threshold: 0.5,
                ..DetectConfig::default()
            },
        )
        .unwrap();
        let d = &r.images[0].detections[0];
        assert!(d.polyline_px.is_some() && d.polyline_mm.is_none() && d.length_mm.is_none());
    }

    #[test]
    fn detections_are_thresholded_mapped_fused_and_drawn() {
        let dir = tempfile::tempdir().unwrap();
        let img = dir.path().join("f.png");
        image::RgbImage::new(16, 8).save(&img).unwrap();
        let config = DetectConfig {
            threshold: 0.5,
            homography: Some(
                Homography::from_matrix([[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]])
                    .unwrap(),
            ),
            fuse: Some(FusionParams {
                min_frames: 2,
                ..FusionParams::default()
            }),
            annotate: Some(dir.path().join("out")),
        };
        let r = detect_images(&mut Two, &[img.clone(), img.clone()], &config).unwrap();
        assert_eq!(r.images.len(), 2);
        assert_eq!(r.images[0].detections.len(), 1);
        assert_eq!(r.images[0].detections[0].centre_mm, Some([2.0, 2.0]));
        let fused = r.fused.as_ref().unwrap();
        assert_eq!(fused.len(), 1);
        assert_eq!(fused[0].frames_seen, Some(2));
        assert_eq!(r.annotated.len(), 2);
        let drawn = image::open(&r.annotated[0]).unwrap().to_rgb8();
        assert_eq!(drawn.get_pixel(2, 2).0, FUSED_COLOUR);
        let json = serde_json::to_value(&r).unwrap();
        assert!(json.get("min_frames").is_none() && json.get("annotated").is_none());
        assert!(json["images"][0]["detections"][0]
            .get("frames_seen")
            .is_none());
        let bad = DetectConfig {
            threshold: 2.0,
            ..DetectConfig::default()
        };
        assert!(detect_images(&mut Two, &[img], &bad).is_err());
        let err = detect_images(&mut Two, &[dir.path().join("no.png")], &config).unwrap_err();
        assert!(err.to_string().contains("no.png"), "{err}");
    }

    /// One box of a box head, at (2, 2)–(6, 6).
    struct Headed;
    impl Detector for Headed {
        fn name(&self) -> String {
            "headed".into()
        }
        fn detect(&mut self, _image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
            Ok(vec![Detection {
                source: crate::DetectionSource::BoxHead,
                ..Detection::boxed(crate::BoundingBox::from_xywh(2.0, 2.0, 4.0, 4.0), 0.4)
            }])
        }
    }

    #[test]
    fn box_head_boxes_are_named_in_the_report_and_drawn_in_their_own_colour() {
        let dir = tempfile::tempdir().unwrap();
        let img = dir.path().join("f.png");
        image::RgbImage::new(16, 8).save(&img).unwrap();
        let config = DetectConfig {
            threshold: 0.25,
            annotate: Some(dir.path().join("out")),
            ..DetectConfig::default()
        };
        let r = detect_images(&mut Headed, &[img], &config).unwrap();
        let json = serde_json::to_value(&r).unwrap();
        assert_eq!(json["images"][0]["detections"][0]["source"], "box_head");
        let drawn = image::open(&r.annotated[0]).unwrap().to_rgb8();
        assert_eq!(drawn.get_pixel(2, 2).0, BOX_HEAD_COLOUR);
        // The detector's own detections carry no `source`.
        let r = detect_images(&mut Two, &[dir.path().join("f.png")], &config).unwrap();
        let json = serde_json::to_value(&r).unwrap();
        assert!(json["images"][0]["detections"][0].get("source").is_none());
    }
}
