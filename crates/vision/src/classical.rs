//! A classical, model-free crack detector: the baseline the trained detector has to beat.
//!
//! Pipeline (all hand-written filters on `f32` buffers, no extra dependency):
//! 1. greyscale (ITU-R 601 luma) and a Gaussian blur (`blur_sigma`);
//! 2. a dark-thin-line response: the morphological black-hat `closing(I) − I` with a square of
//!    radius `line_radius` (cracks are darker than the surface and thinner than `2r + 1` px);
//! 3. a threshold: Otsu's on the response, but never below `min_response` grey levels (so a blank
//!    or smooth image gives nothing) nor below the `response_quantile` of the response;
//! 4. a binary closing (radius `close_radius`) to join broken pieces, then 8-connected components;
//! 5. components are kept if large enough (`min_component_fraction` of the image), long enough
//!    (`min_length_fraction` of `max(H, W)` along their principal axis) and elongated
//!    (`min_elongation`, the ratio of the principal axes of the component's pixels);
//! 6. kept components are grouped like the dataset's box rule: a dilation of radius
//!    `merge_fraction × max(H, W)` decides which belong together, and each group's box is the
//!    tight box of its undilated pixels; boxes under `min_box_fraction` of the image are dropped;
//! 7. score in `[0, 1)`: `contrast / (contrast + contrast_half)` (how far the mean response over
//!    the group's pixels is above the threshold, grey levels: noise just clears the threshold, a
//!    crack clears it by far) times `extent / (extent + extent_half × image diagonal)` (the box
//!    diagonal), best first, at most `max_detections`.
//!
//! Defaults were picked on the val splits of `/work/shared/data/cracks` (COCO mAP@[.5:.95] about
//! 0.32 on crackforest, 0.06 on quaywall, ~0 on uav75, whose straight formwork joints look like
//! cracks and whose real cracks are 1–3 px and faint): a baseline, not a competitor.
//!
//! Boxes follow [`crate::Detector`]'s convention: pixel corners, a box covering pixel `(c, r)`
//! alone is `c, r, c + 1, r + 1`.

use serde::{Deserialize, Serialize};

use crate::{BoundingBox, Detection, Detector, VisionError};

/// Parameters of [`ClassicalDetector`]; the defaults suit the crack datasets (256–512 px images,
/// cracks 1–6 px wide).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ClassicalParams {
    /// Gaussian blur sigma in pixels before the line response (default 1.0; 0 disables).
    pub blur_sigma: f32,
    /// Radius of the square of the black-hat closing (default 4: lines up to ~8 px wide).
    pub line_radius: u32,
    /// The threshold is never below this many grey levels of response (default 12).
    pub min_response: f32,
    /// Radius of the binary closing that joins broken pieces (default 2).
    pub close_radius: u32,
    /// Smallest component kept, as a fraction of the image's pixels (default 0.0003).
    pub min_component_fraction: f32,
    /// Smallest ratio of the component's principal axes (default 3: lines, not blobs).
    pub min_elongation: f32,
    /// Shortest component kept: its length along its principal axis (`√12 ×` the standard
    /// deviation, exact for a straight segment) as a fraction of `max(H, W)` (default 0.03).
    pub min_length_fraction: f32,
    /// The threshold is never below this quantile of the response (default 0.97: at most ~3% of the
    /// pixels are candidate crack pixels).
    pub response_quantile: f32,
    /// Dilation radius that groups components into one crack, as a fraction of `max(H, W)`
    /// (default 0.04: the dataset's rule uses 0.02 on the labelled pixels, but thresholded
    /// responses are more broken than labels, and 0.04 scored better on the val splits).
    pub merge_fraction: f32,
    /// Smallest box kept, as a fraction of the image area (default 0.001, the dataset's rule).
    pub min_box_fraction: f32,
    /// Mean response above the threshold (grey levels) at which the contrast factor of the score is
    /// ½ (default 10).
    pub contrast_half: f32,
    /// Box diagonal, as a fraction of the image diagonal, at which the extent factor of the score
    /// is ½ (default 0.15).
    pub extent_half: f32,
    /// At most this many detections per image (default 20).
    pub max_detections: usize,
}

impl Default for ClassicalParams {
    fn default() -> Self {
        Self {
            blur_sigma: 1.0,
            line_radius: 4,
            min_response: 12.0,
            close_radius: 2,
            min_component_fraction: 0.0003,
            min_elongation: 3.0,
            min_length_fraction: 0.03,
            response_quantile: 0.97,
            merge_fraction: 0.04,
            min_box_fraction: 0.001,
            contrast_half: 10.0,
            extent_half: 0.15,
            max_detections: 20,
        }
    }
}

impl ClassicalParams {
    /// Checks every value is finite and in range.
    pub fn validate(&self) -> Result<(), VisionError> {
        let checks: [(&str, f32, bool, &str); 10] = [
            (
                "min_length_fraction",
                self.min_length_fraction,
                (0.0..=1.0).contains(&self.min_length_fraction),
                "in [0, 1]",
            ),
            (
                "response_quantile",
                self.response_quantile,
                (0.0..=1.0).contains(&self.response_quantile),
                "in [0, 1]",
            ),
            (
                "blur_sigma",
                self.blur_sigma,
                self.blur_sigma >= 0.0 && self.blur_sigma <= 50.0,
                "in [0, 50]",
            ),
            (
                "min_response",
                self.min_response,
                self.min_response >= 0.0,
                "≥ 0",
            ),
            (
                "min_component_fraction",
                self.min_component_fraction,
                (0.0..=1.0).contains(&self.min_component_fraction),
                "in [0, 1]",
            ),
            (
                "min_elongation",
                self.min_elongation,
                self.min_elongation >= 0.0,
                "≥ 0",
            ),
            (
                "merge_fraction",
                self.merge_fraction,
                (0.0..=1.0).contains(&self.merge_fraction),
                "in [0, 1]",
            ),
            (
                "min_box_fraction",
                self.min_box_fraction,
                (0.0..=1.0).contains(&self.min_box_fraction),
                "in [0, 1]",
            ),
            (
                "contrast_half",
                self.contrast_half,
                self.contrast_half > 0.0,
                "> 0",
            ),
            (
                "extent_half",
                self.extent_half,
                self.extent_half > 0.0,
                "> 0",
            ),
        ];
        for (name, value, ok, allowed) in checks {
            if !value.is_finite() || !ok {
                return Err(VisionError::setting(name, f64::from(value), allowed));
            }
        }
        if self.line_radius == 0 || self.line_radius > 64 {
            let value = self.line_radius as f64;
            return Err(VisionError::setting("line_radius", value, "in 1..=64"));
        }
        if self.close_radius > 64 {
            let value = self.close_radius as f64;
            return Err(VisionError::setting("close_radius", value, "in 0..=64"));
        }
        Ok(())
    }
}

/// The edge-based baseline detector (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct ClassicalDetector {
    params: ClassicalParams,
}

impl ClassicalDetector {
    /// A detector with these parameters (validated).
    pub fn new(params: ClassicalParams) -> Result<Self, VisionError> {
        params.validate()?;
        Ok(Self { params })
    }

    /// Its parameters.
    pub fn params(&self) -> &ClassicalParams {
        &self.params
    }
}

impl Detector for ClassicalDetector {
    fn name(&self) -> String {
        "classical".into()
    }

    fn detect(&mut self, image: &image::RgbImage) -> Result<Vec<Detection>, VisionError> {
        self.params.validate()?;
        Ok(detect(image, &self.params))
    }
}

/// A greyscale `f32` image, row-major.
struct Plane {
    w: usize,
    h: usize,
    data: Vec<f32>,
}

impl Plane {
    fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.w + x]
    }
}

fn grey(image: &image::RgbImage) -> Plane {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let data = image
        .pixels()
        .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
        .collect();
    Plane { w, h, data }
}

/// Applies a 1-D operation along rows then columns.
fn separable(p: &Plane, f: &dyn Fn(&[f32], &mut [f32])) -> Plane {
    let (w, h) = (p.w, p.h);
    let mut tmp = vec![0.0f32; w * h];
    for y in 0..h {
        f(&p.data[y * w..(y + 1) * w], &mut tmp[y * w..(y + 1) * w]);
    }
    let mut out = vec![0.0f32; w * h];
    let mut col = vec![0.0f32; h];
    let mut res = vec![0.0f32; h];
    for x in 0..w {
        for y in 0..h {
            col[y] = tmp[y * w + x];
        }
        f(&col, &mut res);
        for y in 0..h {
            out[y * w + x] = res[y];
        }
    }
    Plane { w, h, data: out }
}

fn gaussian_blur(p: &Plane, sigma: f32) -> Plane {
    if sigma <= 0.0 {
        return Plane {
            w: p.w,
            h: p.h,
            data: p.data.clone(),
        };
    }
    let r = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-r..=r)
        .map(|i| (-((i * i) as f32) / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / sum).collect();
    separable(p, &|src, dst| {
        let n = src.len() as isize;
        for (i, d) in dst.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (k, kv) in kernel.iter().enumerate() {
                let j = (i as isize + k as isize - r).clamp(0, n - 1);
                acc += kv * src[j as usize];
            }
            *d = acc;
        }
    })
}

/// Grey max (dilation) or min (erosion) over a square of radius `r`, using only in-image pixels.
fn rank_filter(p: &Plane, r: usize, max: bool) -> Plane {
    separable(p, &|src, dst| {
        let n = src.len();
        for (i, d) in dst.iter_mut().enumerate() {
            let lo = i.saturating_sub(r);
            let hi = (i + r).min(n - 1);
            let window = &src[lo..=hi];
            *d = if max {
                window.iter().copied().fold(f32::MIN, f32::max)
            } else {
                window.iter().copied().fold(f32::MAX, f32::min)
            };
        }
    })
}

fn otsu(values: &[f32], max_value: f32) -> f32 {
    if max_value.is_nan() || max_value <= 0.0 || values.is_empty() {
        return 0.0;
    }
    let mut hist = [0u64; 256];
    for &v in values {
        let b = ((v / max_value) * 255.0).clamp(0.0, 255.0) as usize;
        hist[b] += 1;
    }
    let total = values.len() as f64;
    let sum_all: f64 = hist
        .iter()
        .enumerate()
        .map(|(i, &c)| i as f64 * c as f64)
        .sum();
    let (mut w0, mut sum0, mut best, mut best_t) = (0.0f64, 0.0f64, -1.0f64, 0usize);
    for (t, &c) in hist.iter().enumerate() {
        w0 += c as f64;
        sum0 += t as f64 * c as f64;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let m0 = sum0 / w0;
        let m1 = (sum_all - sum0) / w1;
        let between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if between > best {
            best = between;
            best_t = t;
        }
    }
    (best_t as f32 + 1.0) / 255.0 * max_value
}

/// 8-connected components of `mask` (row-major `w × h`): the label of each pixel (0 = none) and
/// the number of components.
fn label(mask: &[bool], w: usize, h: usize) -> (Vec<u32>, u32) {
    let mut labels = vec![0u32; w * h];
    let mut next = 0u32;
    let mut stack = Vec::new();
    for start in 0..w * h {
        if !mask[start] || labels[start] != 0 {
            continue;
        }
        next += 1;
        labels[start] = next;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if mask[j] && labels[j] == 0 {
                        labels[j] = next;
                        stack.push(j);
                    }
                }
            }
        }
    }
    (labels, next)
}

#[derive(Clone)]
struct Stats {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
    response: f64,
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
}

impl Stats {
    fn new() -> Self {
        Self {
            n: 0.0,
            sx: 0.0,
            sy: 0.0,
            sxx: 0.0,
            sxy: 0.0,
            syy: 0.0,
            response: 0.0,
            x0: usize::MAX,
            y0: usize::MAX,
            x1: 0,
            y1: 0,
        }
    }

    fn add(&mut self, x: usize, y: usize, r: f32) {
        let (fx, fy) = (x as f64, y as f64);
        self.n += 1.0;
        self.sx += fx;
        self.sy += fy;
        self.sxx += fx * fx;
        self.sxy += fx * fy;
        self.syy += fy * fy;
        self.response += f64::from(r);
        self.x0 = self.x0.min(x);
        self.y0 = self.y0.min(y);
        self.x1 = self.x1.max(x);
        self.y1 = self.y1.max(y);
    }

    /// Variances along the principal axes (largest first), pixels counted as unit squares.
    fn principal_variances(&self) -> (f64, f64) {
        let n = self.n;
        let (mx, my) = (self.sx / n, self.sy / n);
        let cxx = self.sxx / n - mx * mx + 1.0 / 12.0;
        let cyy = self.syy / n - my * my + 1.0 / 12.0;
        let cxy = self.sxy / n - mx * my;
        let tr = cxx + cyy;
        let disc = ((cxx - cyy) * (cxx - cyy) / 4.0 + cxy * cxy).sqrt();
        (
            (tr / 2.0 + disc).max(1.0 / 12.0),
            (tr / 2.0 - disc).max(1.0 / 12.0),
        )
    }

    /// Length along the principal axis (exact for a straight segment).
    fn length(&self) -> f64 {
        (12.0 * self.principal_variances().0).sqrt()
    }

    /// Ratio of the principal axes (standard deviations along them).
    fn elongation(&self) -> f64 {
        let (l1, l2) = self.principal_variances();
        (l1 / l2).sqrt()
    }
}

fn detect(image: &image::RgbImage, p: &ClassicalParams) -> Vec<Detection> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    if w == 0 || h == 0 {
        return Vec::new();
    }
    let g = gaussian_blur(&grey(image), p.blur_sigma);
    let r = p.line_radius as usize;
    let closed = rank_filter(&rank_filter(&g, r, true), r, false);
    let response: Vec<f32> = closed
        .data
        .iter()
        .zip(&g.data)
        .map(|(c, v)| (c - v).max(0.0))
        .collect();
    let max_response = response.iter().copied().fold(0.0f32, f32::max);
    let mut sorted = response.clone();
    let q = ((sorted.len() - 1) as f64 * f64::from(p.response_quantile)).round() as usize;
    let (_, quantile, _) = sorted.select_nth_unstable_by(q, f32::total_cmp);
    let threshold = otsu(&response, max_response)
        .max(p.min_response)
        .max(*quantile);
    let mask = Plane {
        w,
        h,
        data: response
            .iter()
            .map(|&v| if v >= threshold { 1.0 } else { 0.0 })
            .collect(),
    };
    let cr = p.close_radius as usize;
    let mask = if cr > 0 {
        rank_filter(&rank_filter(&mask, cr, true), cr, false)
    } else {
        mask
    };
    let binary: Vec<bool> = mask.data.iter().map(|&v| v > 0.5).collect();
    let (labels, count) = label(&binary, w, h);
    let mut stats = vec![Stats::new(); count as usize];
    for y in 0..h {
        for x in 0..w {
            let l = labels[y * w + x];
            if l > 0 {
                stats[l as usize - 1].add(x, y, response[y * w + x]);
            }
        }
    }
    let area = (w * h) as f64;
    let keep: Vec<bool> = stats
        .iter()
        .map(|s| {
            s.n >= f64::from(p.min_component_fraction) * area
                && s.elongation() >= f64::from(p.min_elongation)
                && s.length() >= f64::from(p.min_length_fraction) * w.max(h) as f64
        })
        .collect();
    // Group kept components: dilate them and label again.
    let merge_r = (f64::from(p.merge_fraction) * w.max(h) as f64).round() as usize;
    let kept_mask = Plane {
        w,
        h,
        data: labels
            .iter()
            .map(|&l| {
                if l > 0 && keep[l as usize - 1] {
                    1.0
                } else {
                    0.0
                }
            })
            .collect(),
    };
    let dilated = if merge_r > 0 {
        rank_filter(&kept_mask, merge_r, true)
    } else {
        Plane {
            w,
            h,
            data: kept_mask.data.clone(),
        }
    };
    let dilated_binary: Vec<bool> = dilated.data.iter().map(|&v| v > 0.5).collect();
    let (groups, group_count) = label(&dilated_binary, w, h);
    let mut group_stats = vec![Stats::new(); group_count as usize];
    for y in 0..h {
        for x in 0..w {
            if kept_mask.at(x, y) > 0.5 {
                let gi = groups[y * w + x];
                if gi > 0 {
                    group_stats[gi as usize - 1].add(x, y, response[y * w + x]);
                }
            }
        }
    }
    let diag = (w as f64).hypot(h as f64);
    let mut detections: Vec<Detection> = group_stats
        .iter()
        .filter(|s| s.n > 0.0)
        .filter_map(|s| {
            let bw = (s.x1 - s.x0 + 1) as f64;
            let bh = (s.y1 - s.y0 + 1) as f64;
            if bw * bh < f64::from(p.min_box_fraction) * area {
                return None;
            }
            let contrast = (s.response / s.n - f64::from(threshold)).max(0.0);
            let extent = bw.hypot(bh);
            let score = contrast / (contrast + f64::from(p.contrast_half)) * extent
                / (extent + f64::from(p.extent_half) * diag);
            let bbox = BoundingBox {
                x0: s.x0 as f32,
                y0: s.y0 as f32,
                x1: (s.x1 + 1) as f32,
                y1: (s.y1 + 1) as f32,
            };
            Some(Detection::boxed(bbox, score as f32))
        })
        .collect();
    detections.sort_by(|a, b| b.score.total_cmp(&a.score));
    detections.truncate(p.max_detections);
    detections
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A light, textured surface (grey ~170 ± noise) with a dark crooked line from `start`, moving
    /// right with a random walk in y; returns the image and the line's tight box.
    fn crack_image(w: u32, h: u32, seed: u64) -> (image::RgbImage, BoundingBox) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut img = image::RgbImage::from_fn(w, h, |_, _| {
            let v = 170.0 + rng.random_range(-12.0f32..12.0);
            image::Rgb([v as u8, (v * 0.97) as u8, (v * 0.92) as u8])
        });
        let (x_start, x_end) = (w / 5, 4 * w / 5);
        let mut y = h as f32 / 2.0;
        let (mut bx0, mut by0, mut bx1, mut by1) = (u32::MAX, u32::MAX, 0u32, 0u32);
        for x in x_start..x_end {
            y = (y + rng.random_range(-1.2f32..1.2)).clamp(5.0, h as f32 - 6.0);
            let width = 1 + (x % 3 == 0) as u32;
            for dy in 0..=width {
                let yy = y as u32 + dy;
                let v = 70 + rng.random_range(0..20u8);
                img.put_pixel(x, yy, image::Rgb([v, v, v]));
                bx0 = bx0.min(x);
                bx1 = bx1.max(x + 1);
                by0 = by0.min(yy);
                by1 = by1.max(yy + 1);
            }
        }
        (
            img,
            BoundingBox {
                x0: bx0 as f32,
                y0: by0 as f32,
                x1: bx1 as f32,
                y1: by1 as f32,
            },
        )
    }

    #[test]
    fn finds_a_dark_crooked_line_on_a_noisy_texture() {
        for seed in 0..4 {
            let (img, truth) = crack_image(240, 160, seed);
            let mut det = ClassicalDetector::default();
            assert_eq!(det.name(), "classical");
            let found = det.detect(&img).unwrap();
            assert!(!found.is_empty(), "seed {seed}: nothing found");
            let best = found[0].clone();
            assert!(
                best.bbox.iou(&truth) > 0.5,
                "seed {seed}: {best:?} vs {truth:?} (all {found:?})"
            );
            assert!(best.score > 0.3 && best.score < 1.0, "{best:?}");
            for d in &found {
                assert!(d.score >= 0.0 && d.score < 1.0 && d.bbox.is_finite());
            }
        }
    }

    #[test]
    fn blank_and_noise_images_give_nothing_confident() {
        let mut det = ClassicalDetector::default();
        let blank = image::RgbImage::from_pixel(200, 150, image::Rgb([180, 180, 180]));
        assert!(det.detect(&blank).unwrap().is_empty());
        let black = image::RgbImage::new(64, 64);
        assert!(det.detect(&black).unwrap().is_empty());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let noise = image::RgbImage::from_fn(200, 150, |_, _| {
            let v = rng.random_range(120..220u8);
            image::Rgb([v, v, v])
        });
        for d in det.detect(&noise).unwrap() {
            assert!(d.score < 0.2, "{d:?}");
        }
    }

    #[test]
    fn tiny_and_extreme_images_do_not_panic() {
        let mut det = ClassicalDetector::default();
        for (w, h) in [
            (0, 0),
            (1, 1),
            (2, 3),
            (3, 2),
            (1, 500),
            (700, 1),
            (2000, 3),
            (4, 900),
        ] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(u64::from(w * 31 + h));
            let img = image::RgbImage::from_fn(w, h, |_, _| {
                let v = rng.random_range(0..255u8);
                image::Rgb([v, v, v])
            });
            let found = det.detect(&img).unwrap();
            for d in found {
                assert!(d.bbox.x0 >= 0.0 && d.bbox.x1 <= w as f32 && d.bbox.y1 <= h as f32);
            }
        }
    }

    #[test]
    fn parameters_are_validated_and_serialisable() {
        assert!(ClassicalDetector::new(ClassicalParams::default()).is_ok());
        let bad = [
            ClassicalParams {
                blur_sigma: f32::NAN,
                ..Default::default()
            },
            ClassicalParams {
                line_radius: 0,
                ..Default::default()
            },
            ClassicalParams {
                merge_fraction: 2.0,
                ..Default::default()
            },
            ClassicalParams {
                contrast_half: 0.0,
                ..Default::default()
            },
        ];
        for p in bad {
            assert!(ClassicalDetector::new(p).is_err());
        }
        let json = serde_json::to_string(&ClassicalParams::default()).unwrap();
        let back: ClassicalParams = serde_json::from_str(&json).unwrap();
        assert_eq!(back, ClassicalParams::default());
        let partial: ClassicalParams = serde_json::from_str(r#"{"line_radius": 6}"#).unwrap();
        assert_eq!(partial.line_radius, 6);
        assert_eq!(partial.blur_sigma, 1.0);
    }

    #[test]
    fn otsu_splits_two_modes() {
        let mut v = vec![10.0f32; 100];
        v.extend(vec![200.0f32; 50]);
        let t = otsu(&v, 200.0);
        assert!(t > 10.0 && t <= 200.0, "{t}");
        assert_eq!(otsu(&[], 1.0), 0.0);
    }
}
