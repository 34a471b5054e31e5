//! The real crack photos the renderer draws cracks with: every long, continuous, unbranched
//! crack of the training masks of `crackforest` and `uav75`, cut out along its principal direction
//! and straightened into a strip (photo darkening and mask).

use std::path::{Path, PathBuf};

use crackbot_imaging::coco::CocoDataset;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::SimError;

/// Environment variable naming the folder of real crack photos (holding `crackforest/` and
/// `uav75/`).
pub const CRACKS_DIR_ENV: &str = "CRACKBOT_CRACKS_DIR";

/// The datasets whose training photos and masks give the cracks their appearance.
pub const CRACK_DATASETS: [&str; 2] = ["crackforest", "uav75"];

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
    pub(super) fn across_scale(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, (self.len - 1) as f64);
        let k0 = u.floor() as usize;
        let k1 = (k0 + 1).min(self.len - 1);
        let f = (u - k0 as f64) as f32;
        let local = (self.half_width_px[k0] * (1.0 - f) + self.half_width_px[k1] * f)
            .max(0.5 * self.mean_half_width_px);
        f64::from((local * self.mean_half_width_px).sqrt())
    }

    /// Folds an unbounded column coordinate back into the strip, mirroring at its ends.
    pub(super) fn fold(&self, u: f64) -> f64 {
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

pub(super) fn image_err(path: &Path, message: impl std::fmt::Display) -> SimError {
    SimError::Image {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

impl CrackAssets {
    /// The folder of real crack photos: `$CRACKBOT_CRACKS_DIR` if set, else `cracks/` in the
    /// shared data folder (`crackbot_datasets::data_dir`: `$CRACKBOT_DATA_DIR` or
    /// `<workspace>/../shared/data`).
    pub fn default_dir() -> PathBuf {
        match std::env::var_os(CRACKS_DIR_ENV) {
            Some(d) if !d.is_empty() => PathBuf::from(d),
            _ => crackbot_datasets::data_dir().join(crackbot_datasets::CRACKS),
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
            let coco = CocoDataset::load(&coco_path)?;
            for img in &coco.images {
                let Some(mask_file) = &img.mask_file else {
                    continue;
                };
                let boxes: Vec<[f64; 4]> = coco.annotations_of(img.id).map(|a| a.bbox).collect();
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
#[expect(
    clippy::too_many_lines,
    reason = "one image-processing pass (mask, skeleton, straightening) over shared buffers; not yet split"
)]
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

/// Picks a crack strip for a crack drawn `width_px` wide: one of the few whose real crack is
/// closest in width, so the photo is magnified as little as possible.
pub(super) fn pick_strip<'a>(
    strips: &'a [CrackStrip],
    width_px: f64,
    rng: &mut ChaCha8Rng,
) -> &'a CrackStrip {
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
