//! Camera images of a scene with ground truth: what the robot's camera would see of the plate,
//! the tight boxes of every visible crack, decoy and screw, and the exact plate → image
//! homography.
//!
//! Every pixel is mapped back through the camera's image → plate homography:
//! * off the plate: a dark background;
//! * on it: the material's colour modulated by value noise (a procedural texture), shaded by the
//!   height field of bumps and wavy patches (Lambertian, one light whose direction is drawn per
//!   frame);
//! * cracks carry **real crack appearance**: a crack photographed in the real datasets
//!   (`crackforest`, `uav75`, training split only) is cut out along its principal direction and
//!   straightened into a strip (photo and mask), and the strip is warped along the scene crack's
//!   polyline: arc length `s` along the path maps to the strip's length, the signed distance `d`
//!   across it to the strip's width, scaled so the crack is `width_mm` wide on the plate. The
//!   photo's darkening (pixel over local background) is applied to the plate's colour through the
//!   mask, stronger for deeper cracks, with the groove's wall shadow on the lit side. A zero-width
//!   crack is drawn as a faint one-pixel hairline.
//! * decoys (printed cracks) use the same warped masks but flat ink (the plate colour times the
//!   decoy's reflectivity), without texture or shadow;
//! * screws are drawn last as metal discs with a slot, at their head's height, occluding what is
//!   under them.
//!
//! Then the frame's lighting (gain, a linear gradient and a vignette, whose strength is the
//! camera's `lighting_variation`) and Gaussian sensor noise (`noise_sigma`) are applied. Everything
//! is deterministic from the seed.
//!
//! Ground-truth boxes are COCO-style `[x, y, w, h]` pixel boxes (top-left origin, tight around the
//! pixels, `w = max col − min col + 1`) of the pixels where a crack's or decoy's (unsoftened) mask
//! exceeds 0.5 and no screw covers it; a screw's box is its visible disc. Features that do not
//! show in the image get no box.

use std::path::{Path, PathBuf};

use image::RgbImage;
use nalgebra::Matrix3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::camera::{apply_homography, Camera};
use crate::scene::Scene;
use crate::surface::{Feature, Point};
use crate::SimError;

/// Base colour of a screw head (before shading and lighting), sRGB.
pub const SCREW_GREY: [u8; 3] = [150, 152, 158];

/// Environment variable naming the folder of real crack photos (holding `crackforest/` and
/// `uav75/`).
pub const CRACKS_DIR_ENV: &str = "CRACKBOT_CRACKS_DIR";

/// The datasets whose training photos and masks give the cracks their appearance.
pub const CRACK_DATASETS: [&str; 2] = ["crackforest", "uav75"];

/// What a ground-truth box marks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxKind {
    /// A crack (the only kind annotated in COCO exports).
    Crack,
    /// A printed decoy crack.
    Decoy,
    /// A screw head.
    Screw,
}

impl BoxKind {
    /// The kind's name: `"crack"`, `"decoy"` or `"screw"`.
    pub fn as_str(self) -> &'static str {
        match self {
            BoxKind::Crack => "crack",
            BoxKind::Decoy => "decoy",
            BoxKind::Screw => "screw",
        }
    }
}

/// The ground-truth box of one visible feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroundTruthBox {
    /// What it is.
    pub kind: BoxKind,
    /// Index of the feature in the scene's `features`.
    pub feature_index: usize,
    /// Left edge, pixels (the leftmost pixel's column).
    pub x: f64,
    /// Top edge, pixels (the topmost pixel's row).
    pub y: f64,
    /// Width, pixels.
    pub w: f64,
    /// Height, pixels.
    pub h: f64,
    /// Number of visible pixels of the feature (mask above 0.5, not occluded).
    pub pixels: u64,
    /// The feature's width on the plate, mm (cracks and decoys).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_mm: Option<f64>,
}

impl GroundTruthBox {
    /// `[x, y, w, h]`.
    pub fn bbox(&self) -> [f64; 4] {
        [self.x, self.y, self.w, self.h]
    }

    /// Whether the pixel coordinates `uv` fall inside the box.
    pub fn contains(&self, uv: [f64; 2]) -> bool {
        uv[0] >= self.x && uv[0] <= self.x + self.w && uv[1] >= self.y && uv[1] <= self.y + self.h
    }
}

/// A rendered camera frame with its ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The image.
    pub image: RgbImage,
    /// Boxes of the visible cracks, decoys and screws, in feature order.
    pub boxes: Vec<GroundTruthBox>,
    /// The exact homography from plate mm (z = 0) to pixels.
    pub plate_to_image: Matrix3<f64>,
    /// The seed the frame was rendered with.
    pub seed: u64,
}

impl Frame {
    /// The boxes of one kind.
    pub fn boxes_of(&self, kind: BoxKind) -> impl Iterator<Item = &GroundTruthBox> + '_ {
        self.boxes.iter().filter(move |b| b.kind == kind)
    }
}

/// Knobs of the renderer beyond the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Overrides the camera's `noise_sigma` (grey levels).
    pub noise_sigma: Option<f64>,
    /// Overrides the camera's `lighting_variation`.
    pub lighting_variation: Option<f64>,
    /// Fixes the plate's texture and the crack photos used for each feature across frames (the
    /// same physical plate seen several times); `None`: drawn from the frame's seed too.
    pub appearance_seed: Option<u64>,
    /// Colour of whatever is around the plate, sRGB.
    pub background: [u8; 3],
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            noise_sigma: None,
            lighting_variation: None,
            appearance_seed: None,
            background: [28, 28, 32],
        }
    }
}

/// One real crack, cut out of a photo along its principal direction and straightened: a strip
/// whose row `half` is the crack's centre line.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackStrip {
    /// Where it comes from (`<dataset>/<file_name>`).
    pub source: String,
    /// Length along the crack, source pixels (columns of the strip).
    pub len: usize,
    /// Half-height of the strip, source pixels (rows: `2 * half + 1`).
    pub half: usize,
    /// Mean half-width of the crack, source pixels.
    pub mean_half_width_px: f32,
    /// The photo's luminance over the local background, `len` columns of `2 half + 1` rows
    /// (index `u * rows + row`).
    ratio: Vec<f32>,
    /// The crack mask (0..1), same layout.
    mask: Vec<f32>,
    /// Smoothed local half-width per column, source pixels.
    half_width_px: Vec<f32>,
}

impl CrackStrip {
    fn rows(&self) -> usize {
        2 * self.half + 1
    }

    /// Bilinear sample of `grid` at column `u`, offset `v` from the centre row; `outside` beyond
    /// the strip's rows.
    fn sample(&self, grid: &[f32], u: f64, v: f64, outside: f32) -> f32 {
        let rows = self.rows();
        let r = v + self.half as f64;
        if !(r >= 0.0 && r <= (rows - 1) as f64) {
            return outside;
        }
        let u = u.clamp(0.0, (self.len - 1) as f64);
        let (u0, r0) = (u.floor() as usize, r.floor() as usize);
        let (u1, r1) = ((u0 + 1).min(self.len - 1), (r0 + 1).min(rows - 1));
        let (fu, fr) = ((u - u0 as f64) as f32, (r - r0 as f64) as f32);
        let at = |uu: usize, rr: usize| grid[uu * rows + rr];
        let top = at(u0, r0) * (1.0 - fu) + at(u1, r0) * fu;
        let bottom = at(u0, r1) * (1.0 - fu) + at(u1, r1) * fu;
        top * (1.0 - fr) + bottom * fr
    }

    /// The crack mask at column `u` and offset `v` (0 outside the strip).
    pub fn mask_at(&self, u: f64, v: f64) -> f32 {
        self.sample(&self.mask, u, v, 0.0)
    }

    /// The photo's darkening ratio at column `u` and offset `v` (1 outside the strip).
    pub fn ratio_at(&self, u: f64, v: f64) -> f32 {
        self.sample(&self.ratio, u, v, 1.0)
    }

    /// The across scale at column `u`: the geometric mean of the local and the mean half-width
    /// (linearly interpolated between columns), so local width variations of the real crack
    /// survive, softened.
    fn across_scale(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, (self.len - 1) as f64);
        let k0 = u.floor() as usize;
        let k1 = (k0 + 1).min(self.len - 1);
        let f = (u - k0 as f64) as f32;
        let local = (self.half_width_px[k0] * (1.0 - f) + self.half_width_px[k1] * f)
            .max(0.5 * self.mean_half_width_px);
        f64::from((local * self.mean_half_width_px).sqrt())
    }

    /// Folds an unbounded column coordinate back into the strip, mirroring at its ends.
    fn fold(&self, u: f64) -> f64 {
        let last = (self.len - 1) as f64;
        if last <= 0.0 {
            return 0.0;
        }
        let period = 2.0 * last;
        let x = u.rem_euclid(period);
        if x > last {
            period - x
        } else {
            x
        }
    }
}

/// The real crack photos the renderer draws cracks with.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackAssets {
    dir: PathBuf,
    strips: Vec<CrackStrip>,
}

#[derive(Deserialize)]
struct CocoFile {
    images: Vec<CocoImageEntry>,
    #[serde(default)]
    annotations: Vec<CocoAnnotationEntry>,
}

#[derive(Deserialize)]
struct CocoImageEntry {
    id: u64,
    file_name: String,
    #[serde(default)]
    mask_file: Option<String>,
}

#[derive(Deserialize)]
struct CocoAnnotationEntry {
    image_id: u64,
    bbox: [f64; 4],
}

fn image_err(path: &Path, message: impl std::fmt::Display) -> SimError {
    SimError::Image {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

impl CrackAssets {
    /// The folder of real crack photos: `$CRACKBOT_CRACKS_DIR` if set, else
    /// `<workspace>/../shared/data/cracks`.
    pub fn default_dir() -> PathBuf {
        match std::env::var_os(CRACKS_DIR_ENV) {
            Some(d) if !d.is_empty() => PathBuf::from(d),
            _ => Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
                .join("../shared/data/cracks"),
        }
    }

    /// Loads the assets from [`CrackAssets::default_dir`].
    pub fn load_default() -> Result<CrackAssets, SimError> {
        CrackAssets::load(&CrackAssets::default_dir())
    }

    /// Reads the **training** photos and masks of `dir/crackforest` and `dir/uav75` (their
    /// `train.json`; never the validation split) and cuts a straightened strip out of every
    /// ground-truth crack that is long, mostly continuous and unbranched enough.
    pub fn load(dir: &Path) -> Result<CrackAssets, SimError> {
        if !dir.is_dir() {
            return Err(SimError::Io {
                path: dir.display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!(
                        "crack photo folder not found (it should hold crackforest/ and uav75/ with train.json, images/ and masks/): set {CRACKS_DIR_ENV} or pass the folder"
                    ),
                ),
            });
        }
        let mut strips = Vec::new();
        let mut found = false;
        for dataset in CRACK_DATASETS {
            let root = dir.join(dataset);
            let coco_path = root.join("train.json");
            if !coco_path.is_file() {
                continue;
            }
            found = true;
            let text = std::fs::read_to_string(&coco_path).map_err(SimError::io(&coco_path))?;
            let coco: CocoFile = serde_json::from_str(&text).map_err(|e| SimError::Parse {
                path: coco_path.display().to_string(),
                message: e.to_string(),
            })?;
            for img in &coco.images {
                let Some(mask_file) = &img.mask_file else {
                    continue;
                };
                let boxes: Vec<[f64; 4]> = coco
                    .annotations
                    .iter()
                    .filter(|a| a.image_id == img.id)
                    .map(|a| a.bbox)
                    .collect();
                if boxes.is_empty() {
                    continue;
                }
                let img_path = root.join(&img.file_name);
                let photo = image::open(&img_path)
                    .map_err(|e| image_err(&img_path, e))?
                    .to_rgb8();
                let mask_path = root.join(mask_file);
                let mask_img = image::open(&mask_path)
                    .map_err(|e| image_err(&mask_path, e))?
                    .to_luma8();
                if mask_img.dimensions() != photo.dimensions() {
                    return Err(image_err(
                        &mask_path,
                        format!(
                            "mask is {:?} but the photo is {:?}",
                            mask_img.dimensions(),
                            photo.dimensions()
                        ),
                    ));
                }
                let (w, h) = (photo.width() as usize, photo.height() as usize);
                let luma: Vec<f32> = photo
                    .pixels()
                    .map(|p| {
                        0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])
                    })
                    .collect();
                let mask: Vec<f32> = mask_img
                    .pixels()
                    .map(|p| if p[0] > 0 { 1.0 } else { 0.0 })
                    .collect();
                let source = format!("{dataset}/{}", img.file_name);
                for b in boxes {
                    if let Some(strip) = extract_strip(&luma, &mask, w, h, b, &source) {
                        strips.push(strip);
                    }
                }
            }
        }
        if !found {
            return Err(SimError::Io {
                path: dir.display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    format!(
                        "no crackforest/train.json or uav75/train.json in the crack photo folder: set {CRACKS_DIR_ENV} or pass the folder"
                    ),
                ),
            });
        }
        if strips.is_empty() {
            return Err(image_err(
                dir,
                "no usable crack (long, continuous, unbranched) in the training masks",
            ));
        }
        Ok(CrackAssets {
            dir: dir.to_path_buf(),
            strips,
        })
    }

    /// The folder the assets were read from.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The straightened crack strips.
    pub fn strips(&self) -> &[CrackStrip] {
        &self.strips
    }
}

fn smooth(values: &[f64], radius: usize) -> Vec<f64> {
    let n = values.len();
    (0..n)
        .map(|i| {
            let lo = i.saturating_sub(radius);
            let hi = (i + radius).min(n - 1);
            values[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
        })
        .collect()
}

/// Bilinear sample of a `w × h` grid at continuous pixel coordinates (pixel centres at +0.5);
/// `None` outside.
fn bilinear(grid: &[f32], w: usize, h: usize, x: f64, y: f64) -> Option<f32> {
    let (x, y) = (x - 0.5, y - 0.5);
    if !(x >= 0.0 && y >= 0.0 && x <= (w - 1) as f64 && y <= (h - 1) as f64) {
        return None;
    }
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = ((x - x0 as f64) as f32, (y - y0 as f64) as f32);
    let top = grid[y0 * w + x0] * (1.0 - fx) + grid[y0 * w + x1] * fx;
    let bottom = grid[y1 * w + x0] * (1.0 - fx) + grid[y1 * w + x1] * fx;
    Some(top * (1.0 - fy) + bottom * fy)
}

/// Cuts the crack inside `bbox` out of a photo (`luma`) and its mask and straightens it, or
/// `None` when it is too short, too fragmented, branched or not darker than its surroundings.
fn extract_strip(
    luma: &[f32],
    mask: &[f32],
    w: usize,
    h: usize,
    bbox: [f64; 4],
    source: &str,
) -> Option<CrackStrip> {
    let x0 = bbox[0].floor().max(0.0) as usize;
    let y0 = bbox[1].floor().max(0.0) as usize;
    let x1 = ((bbox[0] + bbox[2]).ceil().max(0.0) as usize).min(w);
    let y1 = ((bbox[1] + bbox[3]).ceil().max(0.0) as usize).min(h);
    let mut pts = Vec::new();
    for y in y0..y1 {
        for x in x0..x1 {
            if mask[y * w + x] > 0.5 {
                pts.push([x as f64 + 0.5, y as f64 + 0.5]);
            }
        }
    }
    if pts.len() < 40 {
        return None;
    }
    let n = pts.len() as f64;
    let c = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let (mut cxx, mut cyy, mut cxy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
        cxx += dx * dx;
        cyy += dy * dy;
        cxy += dx * dy;
    }
    let theta = 0.5 * (2.0 * cxy).atan2(cxx - cyy);
    let a = [theta.cos(), theta.sin()];
    let nrm = [-a[1], a[0]];
    let uv: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| {
            let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
            [dx * a[0] + dy * a[1], dx * nrm[0] + dy * nrm[1]]
        })
        .collect();
    let umin = uv.iter().map(|q| q[0]).fold(f64::INFINITY, f64::min);
    let umax = uv.iter().map(|q| q[0]).fold(f64::NEG_INFINITY, f64::max);
    let len = (umax - umin).floor() as usize + 1;
    if len < 48 {
        return None;
    }
    let mut count = vec![0usize; len];
    let mut sumv = vec![0.0f64; len];
    let mut vmin = vec![f64::INFINITY; len];
    let mut vmax = vec![f64::NEG_INFINITY; len];
    let bin = |u: f64| (((u - umin).floor()) as usize).min(len - 1);
    for q in &uv {
        let b = bin(q[0]);
        count[b] += 1;
        sumv[b] += q[1];
        vmin[b] = vmin[b].min(q[1]);
        vmax[b] = vmax[b].max(q[1]);
    }
    let nonempty: Vec<usize> = (0..len).filter(|&b| count[b] > 0).collect();
    if (nonempty.len() as f64) < 0.75 * len as f64 {
        return None;
    }
    // Centre line: per-bin mean, gaps filled linearly.
    let mut centre = vec![0.0; len];
    for b in 0..len {
        if count[b] > 0 {
            centre[b] = sumv[b] / count[b] as f64;
            continue;
        }
        let prev = nonempty.iter().rev().find(|&&k| k < b).copied();
        let next = nonempty.iter().find(|&&k| k > b).copied();
        centre[b] = match (prev, next) {
            (Some(p), Some(q)) => {
                let (cp, cq) = (sumv[p] / count[p] as f64, sumv[q] / count[q] as f64);
                cp + (cq - cp) * (b - p) as f64 / (q - p) as f64
            }
            (Some(p), None) => sumv[p] / count[p] as f64,
            (None, Some(q)) => sumv[q] / count[q] as f64,
            (None, None) => 0.0,
        };
    }
    let mut counts: Vec<usize> = nonempty.iter().map(|&b| count[b]).collect();
    counts.sort_unstable();
    let hw_med = (counts[counts.len() / 2] as f64 / 2.0).max(0.5);
    let outliers = uv
        .iter()
        .filter(|q| (q[1] - centre[bin(q[0])]).abs() > 2.0 * hw_med + 2.0)
        .count();
    if outliers as f64 > 0.08 * n {
        return None;
    }
    // Steep stretches (the crack turning away from its principal direction by more than about
    // 50°) show as tall runs of pixels in one column, or jumps of the centre line.
    let steep = nonempty
        .iter()
        .filter(|&&b| vmax[b] - vmin[b] + 1.0 > 3.0 * hw_med + 2.0)
        .count()
        + centre
            .windows(2)
            .filter(|c| (c[1] - c[0]).abs() > 1.5)
            .count();
    if steep as f64 > 0.1 * len as f64 {
        return None;
    }
    let centre = smooth(&centre, 2);
    let hw_raw: Vec<f64> = count.iter().map(|&k| k as f64 / 2.0).collect();
    let hw = smooth(&hw_raw, 8);
    let mean_hw = (nonempty.iter().map(|&b| hw[b]).sum::<f64>() / nonempty.len() as f64).max(0.5);
    let hw_max = hw.iter().copied().fold(0.0, f64::max);
    let half = ((hw_max * 2.5 + 4.0).ceil() as usize).clamp(6, 24);
    let rows = 2 * half + 1;
    let mut lum = vec![f32::NAN; len * rows];
    let mut msk = vec![0.0f32; len * rows];
    for (iu, &cu) in centre.iter().enumerate() {
        let u = umin + iu as f64 + 0.5;
        for r in 0..rows {
            let v = cu + r as f64 - half as f64;
            let x = c[0] + u * a[0] + v * nrm[0];
            let y = c[1] + u * a[1] + v * nrm[1];
            if let (Some(l), Some(m)) = (bilinear(luma, w, h, x, y), bilinear(mask, w, h, x, y)) {
                lum[iu * rows + r] = l;
                msk[iu * rows + r] = m;
            }
        }
    }
    // Darkening relative to the local background (non-crack pixels of nearby columns).
    let mut ratio = vec![1.0f32; len * rows];
    let mut contrast = (0.0f64, 0usize);
    for iu in 0..len {
        let (lo, hi) = (iu.saturating_sub(4), (iu + 4).min(len - 1));
        let (mut sum, mut k) = (0.0f64, 0usize);
        for uu in lo..=hi {
            for r in 0..rows {
                let (l, m) = (lum[uu * rows + r], msk[uu * rows + r]);
                if l.is_finite() && m < 0.05 {
                    sum += f64::from(l);
                    k += 1;
                }
            }
        }
        if k == 0 || sum <= 0.0 {
            continue;
        }
        let bg = (sum / k as f64) as f32;
        for r in 0..rows {
            let l = lum[iu * rows + r];
            let q = if l.is_finite() {
                (l / bg).clamp(0.0, 1.5)
            } else {
                1.0
            };
            ratio[iu * rows + r] = q;
            if msk[iu * rows + r] > 0.5 {
                contrast.0 += f64::from(1.0 - q);
                contrast.1 += 1;
            }
        }
    }
    if contrast.1 == 0 || contrast.0 / (contrast.1 as f64) < 0.05 {
        return None;
    }
    Some(CrackStrip {
        source: source.to_string(),
        len,
        half,
        mean_half_width_px: mean_hw as f32,
        ratio,
        mask: msk,
        half_width_px: hw.iter().map(|&v| v as f32).collect(),
    })
}

// ---------------------------------------------------------------------------------------------
// Procedural texture and randomness.

fn mix64(mut h: u64) -> u64 {
    h ^= h >> 33;
    h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^= h >> 33;
    h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
    h ^ (h >> 33)
}

fn hash2(ix: i64, iy: i64, seed: u64) -> f32 {
    let h = mix64(
        seed ^ (ix as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (iy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
    );
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// `x.floor()` as an integer without a libm call (for |x| < 2⁶³).
#[inline]
fn fast_floor(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i - 1
    } else {
        i
    }
}

/// Smooth value noise in [0, 1] at `(x, y)` lattice units.
fn value_noise(x: f64, y: f64, seed: u64) -> f32 {
    let (ix, iy) = (fast_floor(x), fast_floor(y));
    let (fx, fy) = (ix as f64, iy as f64);
    let (tx, ty) = ((x - fx) as f32, (y - fy) as f32);
    let (sx, sy) = (tx * tx * (3.0 - 2.0 * tx), ty * ty * (3.0 - 2.0 * ty));
    let a = hash2(ix, iy, seed);
    let b = hash2(ix + 1, iy, seed);
    let c = hash2(ix, iy + 1, seed);
    let d = hash2(ix + 1, iy + 1, seed);
    let top = a + (b - a) * sx;
    let bottom = c + (d - c) * sx;
    top + (bottom - top) * sy
}

/// The plate's material texture: a relative brightness change at plate point `p` (mm).
fn material_texture(p: Point, seed: u64) -> f32 {
    const OCTAVES: [(f64, f32); 3] = [(14.0, 0.045), (3.0, 0.035), (0.8, 0.025)];
    let mut t = 0.0;
    for (k, (scale, amp)) in OCTAVES.iter().enumerate() {
        let n = value_noise(
            p[0] / scale,
            p[1] / scale,
            seed.wrapping_add(k as u64 * 7919),
        );
        t += amp * (2.0 * n - 1.0);
    }
    t
}

// ---------------------------------------------------------------------------------------------
// Geometry helpers.

/// A polyline prepared for (arc length, signed distance) queries.
struct Path2 {
    a: Vec<Point>,
    dir: Vec<Point>,
    len: Vec<f64>,
    cum: Vec<f64>,
    total: f64,
}

impl Path2 {
    fn new(path: &[Point]) -> Path2 {
        let mut p = Path2 {
            a: Vec::new(),
            dir: Vec::new(),
            len: Vec::new(),
            cum: Vec::new(),
            total: 0.0,
        };
        for s in path.windows(2) {
            let d = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
            let l = (d[0] * d[0] + d[1] * d[1]).sqrt();
            if l <= 1e-12 {
                continue;
            }
            p.a.push(s[0]);
            p.dir.push([d[0] / l, d[1] / l]);
            p.len.push(l);
            p.cum.push(p.total);
            p.total += l;
        }
        p
    }

    /// Arc length `s` of the nearest point (beyond the ends: negative, or above the total) and
    /// signed distance `d` (positive to the left of the direction of travel), plus the segment.
    fn locate(&self, q: Point) -> Option<(f64, f64, usize)> {
        let n = self.a.len();
        let mut best: Option<(f64, f64, f64, usize)> = None;
        for k in 0..n {
            let (a, d) = (self.a[k], self.dir[k]);
            let rel = [q[0] - a[0], q[1] - a[1]];
            let mut t = rel[0] * d[0] + rel[1] * d[1];
            if k > 0 {
                t = t.max(0.0);
            }
            if k + 1 < n {
                t = t.min(self.len[k]);
            }
            let foot = [a[0] + t * d[0], a[1] + t * d[1]];
            let dist2 = (q[0] - foot[0]).powi(2) + (q[1] - foot[1]).powi(2);
            if best.is_none_or(|b| dist2 < b.0) {
                let side = d[0] * rel[1] - d[1] * rel[0];
                let signed = dist2.sqrt().copysign(if side == 0.0 { 1.0 } else { side });
                best = Some((dist2, self.cum[k] + t, signed, k));
            }
        }
        best.map(|b| (b.1, b.2, b.3))
    }

    fn point_at(&self, s: f64) -> Point {
        for k in 0..self.a.len() {
            if s <= self.cum[k] + self.len[k] || k + 1 == self.a.len() {
                let t = s - self.cum[k];
                return [
                    self.a[k][0] + t * self.dir[k][0],
                    self.a[k][1] + t * self.dir[k][1],
                ];
            }
        }
        [0.0, 0.0]
    }
}

/// Pixel rectangle `[c0, c1) × [r0, r1)` covering the plate rectangle `lo..hi` (at height `z`),
/// clipped to the image; `None` if empty.
fn pixel_region(
    cam: &Camera,
    lo: Point,
    hi: Point,
    z: &[f64],
) -> Option<(usize, usize, usize, usize)> {
    let (w, h) = (f64::from(cam.width()), f64::from(cam.height()));
    let mut umin = f64::INFINITY;
    let mut umax = f64::NEG_INFINITY;
    let mut vmin = f64::INFINITY;
    let mut vmax = f64::NEG_INFINITY;
    for &zz in z {
        for p in [
            [lo[0], lo[1]],
            [hi[0], lo[1]],
            [lo[0], hi[1]],
            [hi[0], hi[1]],
        ] {
            match cam.project([p[0], p[1], zz]) {
                Some(uv) => {
                    umin = umin.min(uv[0]);
                    umax = umax.max(uv[0]);
                    vmin = vmin.min(uv[1]);
                    vmax = vmax.max(uv[1]);
                }
                // A corner behind the camera: fall back to the whole image.
                None => {
                    umin = 0.0;
                    vmin = 0.0;
                    umax = w;
                    vmax = h;
                }
            }
        }
    }
    let c0 = (umin - 1.0).floor().clamp(0.0, w) as usize;
    let c1 = (umax + 1.0).ceil().clamp(0.0, w) as usize;
    let r0 = (vmin - 1.0).floor().clamp(0.0, h) as usize;
    let r1 = (vmax + 1.0).ceil().clamp(0.0, h) as usize;
    (c0 < c1 && r0 < r1).then_some((c0, c1, r0, r1))
}

/// Millimetres per pixel around the plate point `p` (geometric mean over x and y).
fn mm_per_px(cam: &Camera, p: Point) -> f64 {
    let h = cam.plate_to_image();
    let d = |a: Point, b: Point| match (apply_homography(&h, a), apply_homography(&h, b)) {
        (Some(x), Some(y)) => ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2)).sqrt(),
        _ => 1.0,
    };
    let dx = d([p[0] - 0.5, p[1]], [p[0] + 0.5, p[1]]);
    let dy = d([p[0], p[1] - 0.5], [p[0], p[1] + 0.5]);
    1.0 / (dx * dy).sqrt().max(1e-9)
}

/// Running bounding box of a feature's visible pixels.
#[derive(Clone, Copy)]
struct BoxAcc {
    c0: usize,
    c1: usize,
    r0: usize,
    r1: usize,
    n: u64,
}

impl BoxAcc {
    fn new() -> BoxAcc {
        BoxAcc {
            c0: usize::MAX,
            c1: 0,
            r0: usize::MAX,
            r1: 0,
            n: 0,
        }
    }
    fn add(&mut self, c: usize, r: usize) {
        self.c0 = self.c0.min(c);
        self.c1 = self.c1.max(c);
        self.r0 = self.r0.min(r);
        self.r1 = self.r1.max(r);
        self.n += 1;
    }
    fn finish(
        self,
        kind: BoxKind,
        feature_index: usize,
        width_mm: Option<f64>,
    ) -> Option<GroundTruthBox> {
        (self.n > 0).then(|| GroundTruthBox {
            kind,
            feature_index,
            x: self.c0 as f64,
            y: self.r0 as f64,
            w: (self.c1 - self.c0 + 1) as f64,
            h: (self.r1 - self.r0 + 1) as f64,
            pixels: self.n,
            width_mm,
        })
    }
}

// ---------------------------------------------------------------------------------------------
// The renderer.

/// A small fast generator for the per-pixel sensor noise (seeded from the frame's ChaCha
/// stream): SplitMix64, and a standard normal approximated by the sum of four uniforms
/// (Irwin–Hall, bounded at ±3.46 σ), plenty for camera noise and cheap.
struct NoiseGen {
    state: u64,
}

impl NoiseGen {
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.state)
    }

    fn gaussian(&mut self) -> f32 {
        let x = self.next_u64();
        let sum = (x & 0xffff) + ((x >> 16) & 0xffff) + ((x >> 32) & 0xffff) + (x >> 48);
        // Four uniforms on [0, 1): mean 2, variance 1/3.
        (sum as f32 / 65536.0 - 2.0) * 3f32.sqrt()
    }
}

/// Pixel → plate mapping without allocation or generic code in the hot loops.
#[derive(Clone, Copy)]
struct InvHomography([f64; 9]);

impl InvHomography {
    fn new(m: &Matrix3<f64>) -> Self {
        InvHomography([
            m[(0, 0)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 0)],
            m[(1, 1)],
            m[(1, 2)],
            m[(2, 0)],
            m[(2, 1)],
            m[(2, 2)],
        ])
    }

    /// The plate point seen through the centre of pixel `(c, r)`.
    #[inline]
    fn at(&self, c: usize, r: usize) -> Option<Point> {
        let (u, v) = (c as f64 + 0.5, r as f64 + 0.5);
        let m = &self.0;
        let z = m[6] * u + m[7] * v + m[8];
        if z.is_nan() || z <= 1e-12 {
            return None;
        }
        Some([
            (m[0] * u + m[1] * v + m[2]) / z,
            (m[3] * u + m[4] * v + m[5]) / z,
        ])
    }
}

/// Lambertian shading of a surface of gradient `(gx, gy)` under `light` (unit vector, z up),
/// relative to the flat plate, with some ambient light.
fn lambert(gx: f64, gy: f64, light: [f64; 3], ambient: f64) -> f32 {
    let norm = (gx * gx + gy * gy + 1.0).sqrt();
    let ndotl = (-gx * light[0] - gy * light[1] + light[2]) / norm;
    (ambient + (1.0 - ambient) * (ndotl / light[2]).max(0.0)).clamp(0.05, 2.0) as f32
}

/// Picks a crack strip for a crack drawn `width_px` wide: one of the few whose real crack is
/// closest in width, so the photo is magnified as little as possible.
fn pick_strip<'a>(strips: &'a [CrackStrip], width_px: f64, rng: &mut ChaCha8Rng) -> &'a CrackStrip {
    let target = (width_px / 2.0).max(0.3);
    let mut order: Vec<(f64, usize)> = strips
        .iter()
        .enumerate()
        .map(|(k, s)| ((target / f64::from(s.mean_half_width_px)).ln().abs(), k))
        .collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let n = order.len().min(8);
    &strips[order[rng.random_range(0..n)].1]
}

/// Renders one camera frame of `scene` with its ground truth, deterministic from `seed`.
///
/// Fails when the scene is invalid, has no camera, or has cracks/decoys and `assets` holds no
/// crack strip.
pub fn render(
    scene: &Scene,
    assets: &CrackAssets,
    opts: &RenderOptions,
    seed: u64,
) -> Result<Frame, SimError> {
    scene.validate()?;
    let spec = scene.camera.as_ref().ok_or_else(|| {
        SimError::Invalid(format!(
            "scene {:?} has no camera: nothing to render",
            scene.name
        ))
    })?;
    let cam = Camera::from_spec(spec)?;
    let has_lines = scene
        .features
        .iter()
        .any(|f| matches!(f, Feature::Crack { .. } | Feature::Decoy { .. }));
    if has_lines && assets.strips.is_empty() {
        return Err(SimError::Invalid(
            "no crack photo strips loaded: cannot draw cracks".into(),
        ));
    }
    let noise_sigma = opts.noise_sigma.unwrap_or(spec.noise_sigma);
    let lighting = opts.lighting_variation.unwrap_or(spec.lighting_variation);
    if !(noise_sigma.is_finite() && noise_sigma >= 0.0) {
        return Err(SimError::Invalid(format!(
            "render noise_sigma must be ≥ 0, got {noise_sigma}"
        )));
    }
    if !(lighting.is_finite() && lighting >= 0.0) {
        return Err(SimError::Invalid(format!(
            "render lighting_variation must be ≥ 0, got {lighting}"
        )));
    }
    let appearance = opts.appearance_seed.unwrap_or(seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);

    // Per-frame light: direction for the shading, gain, gradient, vignette.
    let az: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let el: f64 = rng.random_range(40f64..65.0).to_radians();
    let light = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
    let std_normal = Normal::new(0.0f64, 1.0).map_err(|e| SimError::Invalid(e.to_string()))?;
    let gain = (1.0 + 0.5 * lighting * std_normal.sample(&mut rng)).clamp(0.4, 1.6);
    let grad_strength = lighting * rng.random::<f64>();
    let grad_angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let vignette = 0.8 * lighting * rng.random::<f64>();
    let mut noise_gen = NoiseGen {
        state: rng.random(),
    };

    let (w, h) = (cam.width() as usize, cam.height() as usize);
    let hinv = InvHomography::new(&cam.image_to_plate());
    let [sx, sy] = scene.plate.size_mm;
    let on_plate = |p: Point| p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= sx && p[1] <= sy;

    // 1. Base: background or textured plate.
    let bg = opts.background.map(f32::from);
    let mat = scene.plate.material.colour.map(f32::from);
    let tex_seed = mix64(appearance ^ 0x7e57_u64);
    let mut px: Vec<[f32; 3]> = vec![bg; w * h];
    let mut plate_mask = vec![false; w * h];
    for r in 0..h {
        for c in 0..w {
            if let Some(p) = hinv.at(c, r).filter(|&p| on_plate(p)) {
                let t = 1.0 + material_texture(p, tex_seed);
                px[r * w + c] = [mat[0] * t, mat[1] * t, mat[2] * t];
                plate_mask[r * w + c] = true;
            }
        }
    }

    // 2. Shading of bumps and wavy patches from the height field's gradient.
    for f in &scene.features {
        if !matches!(f, Feature::Bump { .. } | Feature::Wavy { .. }) {
            continue;
        }
        let (lo, hi) = f.footprint();
        let Some((c0, c1, r0, r1)) = pixel_region(&cam, lo, hi, &[0.0]) else {
            continue;
        };
        for r in r0..r1 {
            for c in c0..c1 {
                if !plate_mask[r * w + c] {
                    continue;
                }
                let Some(p) = hinv.at(c, r) else { continue };
                if !(p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1]) {
                    continue;
                }
                let e = 0.05;
                let gx =
                    (f.height_mm([p[0] + e, p[1]]) - f.height_mm([p[0] - e, p[1]])) / (2.0 * e);
                let gy =
                    (f.height_mm([p[0], p[1] + e]) - f.height_mm([p[0], p[1] - e])) / (2.0 * e);
                if gx == 0.0 && gy == 0.0 {
                    continue;
                }
                let shade = lambert(gx, gy, light, 0.45);
                for ch in &mut px[r * w + c] {
                    *ch *= shade;
                }
            }
        }
    }

    // 3. Which pixels the screw heads cover (the ray meets the head's top at its height).
    let mut screw_at: Vec<u32> = vec![0; w * h];
    let mut screw_regions = Vec::new();
    for (i, f) in scene.features.iter().enumerate() {
        let Feature::Screw {
            centre,
            head_diameter_mm,
            height_mm,
        } = f
        else {
            continue;
        };
        let rad = head_diameter_mm / 2.0;
        let lo = [centre[0] - rad, centre[1] - rad];
        let hi = [centre[0] + rad, centre[1] + rad];
        let Some(region) = pixel_region(&cam, lo, hi, &[0.0, *height_mm]) else {
            continue;
        };
        let (c0, c1, r0, r1) = region;
        for r in r0..r1 {
            for c in c0..c1 {
                let Some(p) = cam.pixel_to_plane([c as f64 + 0.5, r as f64 + 0.5], *height_mm)
                else {
                    continue;
                };
                if (p[0] - centre[0]).hypot(p[1] - centre[1]) < rad {
                    screw_at[r * w + c] = i as u32 + 1;
                }
            }
        }
        screw_regions.push((i, region));
    }

    // 4. Cracks and decoys, warped from the real crack strips.
    let mut boxes: Vec<GroundTruthBox> = Vec::new();
    for (i, f) in scene.features.iter().enumerate() {
        let (path, width, depth, ink) = match f {
            Feature::Crack {
                path,
                width_mm,
                depth_mm,
                ..
            } => (path, *width_mm, *depth_mm, None),
            Feature::Decoy {
                path,
                width_mm,
                reflectivity,
            } => (path, *width_mm, 0.0, Some(*reflectivity)),
            _ => continue,
        };
        let geo = Path2::new(path);
        if geo.a.is_empty() {
            continue;
        }
        let mid = geo.point_at(geo.total / 2.0);
        let px_mm = mm_per_px(&cam, mid);
        // Draw at least one pixel wide; thinner cracks are fainter (their pixel coverage).
        let w_eff = width.max(px_mm);
        let coverage = (width.max(0.35 * px_mm) / w_eff).min(1.0) as f32;
        let half_w = w_eff / 2.0;
        let mut frng = ChaCha8Rng::seed_from_u64(mix64(appearance ^ mix64(i as u64 + 1)));
        let strip = pick_strip(&assets.strips, w_eff / px_mm, &mut frng);
        let flip_v = if frng.random::<bool>() { -1.0 } else { 1.0 };
        let dir_u = if frng.random::<bool>() { -1.0 } else { 1.0 };
        // Isotropic warp: one source pixel is as long along the crack as across it.
        let mm_per_src = half_w / f64::from(strip.mean_half_width_px);
        let needed = geo.total / mm_per_src;
        let last = (strip.len - 1) as f64;
        let u0 = if needed < last {
            let start = frng.random_range(0.0..=(last - needed));
            if dir_u > 0.0 {
                start
            } else {
                start + needed
            }
        } else {
            frng.random_range(0.0..=last)
        };
        // The crack narrows over its last few widths at each end.
        let taper_len = (3.0 * w_eff).min(0.2 * geo.total).max(1e-9);
        let d_max = 2.5 * half_w + 2.0 * px_mm;
        let depth_factor = (0.6 + 0.4 * (1.0 - (-depth / 2.0).exp())) as f32;
        let light_h = [light[0], light[1]];
        let shadow_per_n = depth / el.tan();
        let (mut lo, mut hi) = f.footprint();
        lo = [lo[0] - d_max, lo[1] - d_max];
        hi = [hi[0] + d_max, hi[1] + d_max];
        let mut acc = BoxAcc::new();
        let Some((c0, c1, r0, r1)) = pixel_region(&cam, lo, hi, &[0.0]) else {
            continue;
        };
        for r in r0..r1 {
            for c in c0..c1 {
                let k = r * w + c;
                if !plate_mask[k] {
                    continue;
                }
                let Some(p) = hinv.at(c, r) else { continue };
                let Some((s, d, seg)) = geo.locate(p) else {
                    continue;
                };
                if s < 0.0 || s > geo.total || d.abs() > d_max {
                    continue;
                }
                let taper = ((s.min(geo.total - s) / taper_len).clamp(0.0, 1.0))
                    .powf(0.6)
                    .max(0.2);
                let u = strip.fold(u0 + dir_u * s / mm_per_src);
                let g = strip.across_scale(u);
                let v = flip_v * d * g / (half_w * taper);
                let m = strip.mask_at(u, v);
                if m <= 0.0 {
                    continue;
                }
                if m > 0.5 && screw_at[k] == 0 {
                    acc.add(c, r);
                }
                // Rendered pixels per source pixel across: sharpen the mask's edge to ~1 pixel.
                let sigma = (half_w * taper / g / px_mm) as f32;
                let alpha = if sigma > 1.0 {
                    (0.5 + (m - 0.5) * sigma).clamp(0.0, 1.0)
                } else {
                    m
                } * coverage;
                let pix = &mut px[k];
                match ink {
                    Some(refl) => {
                        let ink = [refl as f32, refl as f32, (refl as f32 * 1.08).min(1.0)];
                        for (ch, t) in pix.iter_mut().zip(ink) {
                            *ch *= 1.0 - alpha * (1.0 - t);
                        }
                    }
                    None => {
                        let ratio = strip.ratio_at(u, v);
                        let mut dark =
                            alpha * depth_factor * (0.25 + 0.9 * (1.0 - ratio)).clamp(0.2, 0.9);
                        // The wall on the light's side shades the floor next to it.
                        let nrm = [-geo.dir[seg][1], geo.dir[seg][0]];
                        let towards = nrm[0] * light_h[0] + nrm[1] * light_h[1];
                        let shadow_len = shadow_per_n * towards.abs();
                        if width > 0.0 && d * towards.signum() > half_w * taper - shadow_len {
                            dark += 0.3 * alpha * (1.0 - dark);
                        }
                        for ch in pix.iter_mut() {
                            *ch *= 1.0 - dark.min(0.95);
                        }
                    }
                }
            }
        }
        let kind = if ink.is_some() {
            BoxKind::Decoy
        } else {
            BoxKind::Crack
        };
        boxes.extend(acc.finish(kind, i, Some(width)));
    }

    // 5. Screws on top.
    let grey = SCREW_GREY.map(f32::from);
    for (i, (c0, c1, r0, r1)) in screw_regions {
        let Feature::Screw {
            centre,
            head_diameter_mm,
            height_mm,
        } = &scene.features[i]
        else {
            continue;
        };
        let rad = head_diameter_mm / 2.0;
        let mut frng = ChaCha8Rng::seed_from_u64(mix64(appearance ^ mix64(i as u64 + 1)));
        let slot: f64 = frng.random_range(0.0..std::f64::consts::PI);
        let (ss, sc) = slot.sin_cos();
        let mut acc = BoxAcc::new();
        for r in r0..r1 {
            for c in c0..c1 {
                let k = r * w + c;
                if screw_at[k] != i as u32 + 1 {
                    continue;
                }
                let Some(p) = cam.pixel_to_plane([c as f64 + 0.5, r as f64 + 0.5], *height_mm)
                else {
                    continue;
                };
                let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                // Domed head h (1 − 0.4 r²/R²): gradient −0.8 h (dx, dy)/R².
                let k_dome = 0.8 * height_mm / (rad * rad);
                let mut shade = lambert(-k_dome * dx, -k_dome * dy, light, 0.45);
                let along = dx * sc + dy * ss;
                let across = -dx * ss + dy * sc;
                if across.abs() < 0.09 * head_diameter_mm && along.abs() < 0.38 * head_diameter_mm {
                    shade *= 0.35;
                }
                if dx.hypot(dy) > 0.9 * rad {
                    shade *= 0.8;
                }
                px[k] = [grey[0] * shade, grey[1] * shade, grey[2] * shade];
                acc.add(c, r);
            }
        }
        boxes.extend(acc.finish(BoxKind::Screw, i, None));
    }
    boxes.sort_by_key(|b| b.feature_index);

    // 6. Lighting, sensor noise, quantisation.
    let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
    let diag = (cx * cx + cy * cy).sqrt();
    let (gs, gc) = grad_angle.sin_cos();
    let sigma = noise_sigma as f32;
    let mut raw = vec![0u8; w * h * 3];
    for (r, (row_out, row_in)) in raw
        .chunks_exact_mut(3 * w)
        .zip(px.chunks_exact(w))
        .enumerate()
    {
        let dy = (r as f64 + 0.5 - cy) / diag;
        for (c, (out, p)) in row_out.chunks_exact_mut(3).zip(row_in).enumerate() {
            let dx = (c as f64 + 0.5 - cx) / diag;
            let light_factor = (gain
                * (1.0 + grad_strength * (dx * gc + dy * gs))
                * (1.0 - 2.0 * vignette * (dx * dx + dy * dy)))
                .max(0.0) as f32;
            for (o, &v) in out.iter_mut().zip(p) {
                let mut v = v * light_factor;
                if sigma > 0.0 {
                    v += sigma * noise_gen.gaussian();
                }
                // Round to nearest (the cast truncates a value already in [0.5, 255.5]).
                *o = (v.clamp(0.0, 255.0) + 0.5) as u8;
            }
        }
    }
    let image = RgbImage::from_raw(cam.width(), cam.height(), raw)
        .ok_or_else(|| SimError::Invalid("image buffer of the wrong size".into()))?;
    Ok(Frame {
        image,
        boxes,
        plate_to_image: cam.plate_to_image(),
        seed,
    })
}

// ---------------------------------------------------------------------------------------------
// Writing frames and datasets.

fn matrix_rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

fn categories() -> serde_json::Value {
    json!([{ "id": 1, "name": "crack", "supercategory": "defect" }])
}

fn crack_annotations(frame: &Frame, image_id: u64, first_id: u64) -> Vec<serde_json::Value> {
    frame
        .boxes_of(BoxKind::Crack)
        .enumerate()
        .map(|(k, b)| {
            json!({
                "id": first_id + k as u64,
                "image_id": image_id,
                "category_id": 1,
                "bbox": b.bbox(),
                "area": b.w * b.h,
                "iscrowd": 0,
                "feature_index": b.feature_index,
                "width_mm": b.width_mm,
                "crack_pixels": b.pixels,
            })
        })
        .collect()
}

/// The JSON description of a frame saved as `file_name`: size, seed, every ground-truth box,
/// the plate → image homography (3 × 3, row-major), and COCO-style `images`, `annotations`
/// (cracks only) and `categories`.
pub fn frame_json(frame: &Frame, file_name: &str) -> serde_json::Value {
    let (width, height) = frame.image.dimensions();
    json!({
        "file_name": file_name,
        "width": width,
        "height": height,
        "seed": frame.seed,
        "plate_to_image": matrix_rows(&frame.plate_to_image),
        "boxes": frame.boxes,
        "images": [{ "id": 1, "file_name": file_name, "width": width, "height": height }],
        "annotations": crack_annotations(frame, 1, 1),
        "categories": categories(),
    })
}

/// Writes `dir/<stem>.png` and `dir/<stem>.json` ([`frame_json`]), creating `dir`.
pub fn write_frame(frame: &Frame, dir: &Path, stem: &str) -> Result<(), SimError> {
    std::fs::create_dir_all(dir).map_err(SimError::io(dir))?;
    let png = dir.join(format!("{stem}.png"));
    frame
        .image
        .save_with_format(&png, image::ImageFormat::Png)
        .map_err(|e| image_err(&png, e))?;
    let json_path = dir.join(format!("{stem}.json"));
    let text = serde_json::to_string_pretty(&frame_json(frame, &format!("{stem}.png")))
        .map_err(|e| image_err(&json_path, e))?;
    std::fs::write(&json_path, text).map_err(SimError::io(&json_path))?;
    Ok(())
}

/// A COCO detection dataset of frames saved under the given file names: image ids 1, 2, …,
/// annotation ids from 1, one category `crack` (id 1). Only cracks are annotated: decoys and
/// screws are not cracks. Readable by `crackbot eval-detector --coco FILE --images DIR`.
pub fn coco_dataset(frames: &[(&str, &Frame)]) -> serde_json::Value {
    let mut images = Vec::new();
    let mut annotations = Vec::new();
    for (k, (file_name, frame)) in frames.iter().enumerate() {
        let id = k as u64 + 1;
        let (width, height) = frame.image.dimensions();
        images.push(json!({
            "id": id,
            "file_name": file_name,
            "width": width,
            "height": height,
            "seed": frame.seed,
            "plate_to_image": matrix_rows(&frame.plate_to_image),
        }));
        let first = annotations.len() as u64 + 1;
        annotations.extend(crack_annotations(frame, id, first));
    }
    json!({
        "info": { "description": "crackbot-sim rendered frames", "version": "1" },
        "images": images,
        "annotations": annotations,
        "categories": categories(),
    })
}

/// Writes `frames` as a COCO dataset: `dir/images/frame_NNNN.png` (with their
/// [`write_frame`] JSON) and `dir/coco.json`; returns the path of `coco.json` (pass
/// `--images dir/images`).
pub fn write_coco_dataset(frames: &[Frame], dir: &Path) -> Result<PathBuf, SimError> {
    let images = dir.join("images");
    let names: Vec<String> = (0..frames.len()).map(|k| format!("frame_{k:04}")).collect();
    for (frame, stem) in frames.iter().zip(&names) {
        write_frame(frame, &images, stem)?;
    }
    let files: Vec<String> = names.iter().map(|s| format!("{s}.png")).collect();
    let entries: Vec<(&str, &Frame)> = files.iter().map(String::as_str).zip(frames).collect();
    let coco_path = dir.join("coco.json");
    let text = serde_json::to_string_pretty(&coco_dataset(&entries))
        .map_err(|e| image_err(&coco_path, e))?;
    std::fs::write(&coco_path, text).map_err(SimError::io(&coco_path))?;
    Ok(coco_path)
}
