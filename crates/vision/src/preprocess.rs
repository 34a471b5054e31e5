//! The letterbox contract between a frame and the detector's input tensor, and the way back from the
//! detector's output to boxes in the frame (`models/detector/MODEL_CARD.md` states the same
//! contract; `models/detector/contract.py` implements it in numpy).
//!
//! For an RGB8 image `W × H` and input size `S`:
//! 1. `s = S / max(W, H)`, `nw = max(1, floor(W·s + 0.5))`, `nh = max(1, floor(H·s + 0.5))`;
//! 2. bilinear resize to `nw × nh` with half-pixel centres and no antialiasing (source coordinate
//!    `(o + 0.5)·W/nw − 0.5`, clamped to the image), in `f32` on 0–255 values, then ÷ 255;
//! 3. placed at the top-left of an `S × S` canvas whose other pixels are 0.5;
//! 4. NCHW `f32` `[1, 3, S, S]`, channels R, G, B.
//!
//! The model returns `[1, N, 5]` rows `x0, y0, x1, y1, score` in canvas pixels; [`postprocess`]
//! keeps rows scoring at least the threshold, divides the corners by `s`, clips them to the image,
//! and runs class-agnostic NMS.

use crate::boxes::{nms, BoundingBox, Detection};
use crate::VisionError;

/// Boxes smaller than this fraction of the image are dropped (the dataset rule's 0.1%).
pub const MIN_AREA_FRACTION: f32 = 0.001;

/// How an image was fitted into the square input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Letterbox {
    /// Input side `S` in pixels.
    pub size: usize,
    /// Scale from image to canvas pixels.
    pub scale: f32,
    /// Resized width in the canvas.
    pub width: usize,
    /// Resized height in the canvas.
    pub height: usize,
    /// Original image width.
    pub image_width: u32,
    /// Original image height.
    pub image_height: u32,
}

impl Letterbox {
    /// The letterbox of a `width × height` image into `size × size`.
    pub fn new(width: u32, height: u32, size: usize) -> Result<Self, VisionError> {
        if width == 0 || height == 0 {
            return Err(VisionError::EmptyImage { width, height });
        }
        if size == 0 {
            return Err(VisionError::setting("input size", 0.0, "≥ 1 px"));
        }
        let scale = size as f32 / width.max(height) as f32;
        let fit = |v: u32| ((v as f32 * scale + 0.5).floor() as usize).clamp(1, size);
        Ok(Self {
            size,
            scale,
            width: fit(width),
            height: fit(height),
            image_width: width,
            image_height: height,
        })
    }
}

/// Letterboxes `image` into a `[1, 3, size, size]` tensor (row-major NCHW), returning the tensor
/// data and the [`Letterbox`] needed to map boxes back.
pub fn letterbox(
    image: &image::RgbImage,
    size: usize,
) -> Result<(Vec<f32>, Letterbox), VisionError> {
    let lb = Letterbox::new(image.width(), image.height(), size)?;
    let (w, h) = (image.width() as usize, image.height() as usize);
    let src = image.as_raw();
    let plane = size * size;
    let mut out = vec![0.5f32; 3 * plane];
    // Source coordinates and weights of every output column and row.
    let axis = |n_out: usize, n_in: usize| -> Vec<(usize, usize, f32)> {
        (0..n_out)
            .map(|o| {
                let s = ((o as f32 + 0.5) * n_in as f32 / n_out as f32 - 0.5)
                    .clamp(0.0, (n_in - 1) as f32);
                let i0 = s.floor() as usize;
                let i1 = (i0 + 1).min(n_in - 1);
                (i0, i1, s - i0 as f32)
            })
            .collect()
    };
    let xs = axis(lb.width, w);
    let ys = axis(lb.height, h);
    for (oy, &(y0, y1, fy)) in ys.iter().enumerate() {
        for (ox, &(x0, x1, fx)) in xs.iter().enumerate() {
            for c in 0..3 {
                let p = |y: usize, x: usize| f32::from(src[(y * w + x) * 3 + c]);
                let top = (1.0 - fx) * p(y0, x0) + fx * p(y0, x1);
                let bottom = (1.0 - fx) * p(y1, x0) + fx * p(y1, x1);
                out[c * plane + oy * size + ox] = ((1.0 - fy) * top + fy * bottom) / 255.0;
            }
        }
    }
    Ok((out, lb))
}

/// Post-processing parameters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PostprocessParams {
    /// Rows scoring below are dropped (0.25 to act on, 0.001 for mAP evaluation).
    pub score_threshold: f32,
    /// NMS IoU threshold.
    pub iou_threshold: f32,
    /// Most detections kept.
    pub max_detections: usize,
    /// Crack-map detections whose box covers less of the image than this fraction are dropped:
    /// the crack datasets' rule ([`crate::crack_map::MIN_AREA_FRACTION`]). A thin crack
    /// running along a pixel axis has a small box however long it is; the robot, which touches
    /// each crack's centre line, sets 0 and keeps every crack with one.
    pub min_area_fraction: f32,
    /// Add a crack-map model's box-head boxes after the crack map's ([`crate::box_head`]):
    /// boxes in the crack photos' own convention, for box metrics (`eval-detector`,
    /// [`crate::benchmark::map_params`]) and `crackbot detect --box-head`. Off by default: the
    /// robot touches the crack map's cracks only, and the head was never checked on its scenes.
    pub box_head: bool,
}

impl Default for PostprocessParams {
    fn default() -> Self {
        Self {
            score_threshold: 0.25,
            iou_threshold: 0.5,
            max_detections: 100,
            min_area_fraction: MIN_AREA_FRACTION,
            box_head: false,
        }
    }
}

/// Decodes the model's `[N, 5]` rows (`x0, y0, x1, y1, score` in canvas pixels) into detections in
/// image pixels. Rows with a non-finite value are dropped.
pub fn postprocess(
    rows: &[f32],
    lb: &Letterbox,
    params: &PostprocessParams,
) -> Result<Vec<Detection>, VisionError> {
    if !rows.len().is_multiple_of(5) {
        return Err(VisionError::Runtime(format!(
            "model output has {} values, not rows of 5 (x0, y0, x1, y1, score)",
            rows.len()
        )));
    }
    let (w, h) = (lb.image_width as f32, lb.image_height as f32);
    let candidates = rows
        .chunks_exact(5)
        .filter(|r| r[4] >= params.score_threshold && r.iter().all(|v| v.is_finite()))
        .map(|r| {
            let bbox = BoundingBox {
                x0: r[0] / lb.scale,
                y0: r[1] / lb.scale,
                x1: r[2] / lb.scale,
                y1: r[3] / lb.scale,
            };
            Detection::boxed(bbox.clipped(w, h), r[4])
        })
        .collect();
    Ok(nms(candidates, params.iou_threshold, params.max_detections))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn letterbox_geometry_and_padding() {
        let img = image::RgbImage::from_fn(480, 320, |x, y| {
            image::Rgb([(x % 256) as u8, (y % 256) as u8, 200])
        });
        let (t, lb) = letterbox(&img, 320).unwrap();
        assert_eq!((lb.width, lb.height), (320, 213));
        assert!((lb.scale - 320.0 / 480.0).abs() < 1e-7);
        assert_eq!(t.len(), 3 * 320 * 320);
        // Below the resized image: padding.
        assert_eq!(t[320 * 300 + 10], 0.5);
        // Blue channel is constant 200 inside the image.
        let plane = 320 * 320;
        assert!((t[2 * plane + 100 * 320 + 100] - 200.0 / 255.0).abs() < 1e-6);
        // Same size: the identity (half-pixel centres land on the pixels).
        let small = image::RgbImage::from_fn(4, 4, |x, y| image::Rgb([(x * 40 + y) as u8, 0, 0]));
        let (t, lb) = letterbox(&small, 4).unwrap();
        assert_eq!(lb.scale, 1.0);
        for y in 0..4 {
            for x in 0..4 {
                assert!((t[y * 4 + x] * 255.0 - (x * 40 + y) as f32).abs() < 1e-4);
            }
        }
        assert!(letterbox(&image::RgbImage::new(0, 5), 320).is_err());
        // A 1-pixel-high strip still gets a row.
        let strip = image::RgbImage::new(1000, 1);
        let (_, lb) = letterbox(&strip, 320).unwrap();
        assert_eq!((lb.width, lb.height), (320, 1));
    }

    #[test]
    fn postprocess_maps_back_clips_and_suppresses() {
        let lb = Letterbox::new(640, 480, 320).unwrap();
        let rows = [
            10.0,
            10.0,
            50.0,
            50.0,
            0.9, // kept, ×2
            11.0,
            11.0,
            51.0,
            51.0,
            0.8, // suppressed by the first
            300.0,
            200.0,
            400.0,
            260.0,
            0.7, // clipped to the image
            0.0,
            0.0,
            5.0,
            5.0,
            0.1, // below threshold
            f32::NAN,
            0.0,
            5.0,
            5.0,
            0.95, // dropped
        ];
        let d = postprocess(&rows, &lb, &PostprocessParams::default()).unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(
            d[0].bbox,
            BoundingBox {
                x0: 20.0,
                y0: 20.0,
                x1: 100.0,
                y1: 100.0
            }
        );
        assert_eq!(d[1].bbox.x1, 640.0);
        assert_eq!(d[1].bbox.y1, 480.0);
        assert!(postprocess(&rows[..7], &lb, &PostprocessParams::default()).is_err());
    }
}
