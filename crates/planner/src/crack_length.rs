//! The paper's eq. 1: the mean crack length from binary crack images, `L_i = A_i / w̄`,
//! `L̄ = Σ L_i / N_c`, with the mean width `w̄` measured from the masks themselves.
//!
//! The paper counted the crack ("black") pixels `A_i` of 30 images, "inspected" the crack width
//! `w̄ = 20 px` by hand and divided. Here both come from the masks:
//!
//! * `A_i`: the crack pixels of mask `i`;
//! * the centre line: the mask thinned to one pixel ([`skeleton`]: Zhang–Suen's two alternating
//!   sub-iterations, each pixel removed only while it is *simple*, so a crack never breaks
//!   or vanishes, and line ends are kept);
//! * its length `S_i` ([`skeleton_length`]): 1 per horizontal/vertical link, √2 per diagonal link
//!   that no 4-connected pair of links replaces, plus half a pixel at each line end (a straight
//!   run of `n` pixels is `n` long; a lone pixel is 1);
//! * the image's width `w_i = A_i / S_i` (area over centre-line length) and `w̄ = mean w_i` over
//!   the `N_c` masks that hold a crack (the paper: one width for all images);
//! * a second, independent width for comparison: the Euclidean distance transform `d` at the
//!   centre-line pixels, `2d − 1` (1 for a one-pixel line, 3 for a three-pixel one), averaged per
//!   image and then over images ([`CrackLengthEstimate::mean_distance_width_px`]).
//!
//! Then `L_i = A_i / w̄` and `L̄ = mean L_i`, exactly eq. 1. (With `w̄` the pooled `ΣA/ΣS`, `L̄`
//! would be the mean centre-line length `mean S_i`, reported beside it.)

use serde::Serialize;

use crackbot_imaging::thinning;

use crate::error::PlanError;

/// The figures the paper gives for eq. 1 and 2 (section III-C): `Ā = 2961` black pixels of 51 529
/// (227 × 227) per image, `w̄ = 20 px`, `L̄ = 148.06 px`, `N_c = 30` images, `h = 480 px` (the
/// camera frame's height).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperEq1 {
    /// Mean crack pixels per image.
    pub mean_area_px: f64,
    /// Pixels per image.
    pub image_px: f64,
    /// Side of the (square) dataset images, pixels.
    pub image_side_px: f64,
    /// Mean crack width, pixels (measured by hand).
    pub mean_width_px: f64,
    /// Mean crack length, pixels.
    pub mean_length_px: f64,
    /// Images used.
    pub n_c: usize,
    /// Height of the camera frame that eq. 2 divides, pixels.
    pub camera_height_px: f64,
}

/// The paper's eq. 1 and 2 figures.
pub const PAPER_EQ1: PaperEq1 = PaperEq1 {
    mean_area_px: 2961.0,
    image_px: 51529.0,
    image_side_px: 227.0,
    mean_width_px: 20.0,
    mean_length_px: 148.06,
    n_c: 30,
    camera_height_px: 480.0,
};

/// A binary crack image: `true` is crack. Row-major, `width × height`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BinaryMask {
    width: usize,
    height: usize,
    pixels: Vec<bool>,
}

impl BinaryMask {
    /// A mask of `width × height` pixels (both ≥ 1), row-major.
    pub fn new(width: usize, height: usize, pixels: Vec<bool>) -> Result<Self, PlanError> {
        if width == 0 || height == 0 {
            return Err(PlanError::InvalidMask {
                index: None,
                reason: format!("a mask needs at least one pixel, got {width}×{height}"),
            });
        }
        if width.checked_mul(height) != Some(pixels.len()) {
            return Err(PlanError::InvalidMask {
                index: None,
                reason: format!("{} pixels given for a {width}×{height} mask", pixels.len()),
            });
        }
        Ok(BinaryMask {
            width,
            height,
            pixels,
        })
    }

    /// A `width × height` mask (both ≥ 1) with `f(x, y)` at each pixel.
    pub fn from_fn(
        width: usize,
        height: usize,
        f: impl Fn(usize, usize) -> bool,
    ) -> Result<Self, PlanError> {
        let pixels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect();
        Self::new(width, height, pixels)
    }

    /// Width, pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height, pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The pixels, row-major.
    pub fn pixels(&self) -> &[bool] {
        &self.pixels
    }

    /// The crack pixel at column `x`, row `y` (`false` outside).
    pub fn get(&self, x: isize, y: isize) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.pixels[y as usize * self.width + x as usize]
    }

    /// Crack pixels, `A_i`.
    pub fn crack_pixels(&self) -> usize {
        self.pixels.iter().filter(|&&p| p).count()
    }
}

/// What eq. 1 needs from one mask.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MaskMeasure {
    /// Image width, pixels.
    pub image_width_px: usize,
    /// Image height, pixels.
    pub image_height_px: usize,
    /// Crack pixels, `A_i`.
    pub area_px: usize,
    /// Pixels of the centre line.
    pub skeleton_px: usize,
    /// Length of the centre line `S_i`, pixels.
    pub skeleton_length_px: f64,
    /// `A_i / S_i`, pixels (0 for an empty mask).
    pub width_px: f64,
    /// Mean of `2d − 1` over the centre line, `d` the Euclidean distance to the nearest
    /// non-crack pixel (0 for an empty mask).
    pub distance_width_px: f64,
}

/// Measures one mask: area, centre line, widths.
pub fn measure_mask(mask: &BinaryMask) -> MaskMeasure {
    let area = mask.crack_pixels();
    let skel = skeleton(mask);
    let skeleton_px = skel.crack_pixels();
    let length = skeleton_length(&skel);
    let dist2 = distance_squared_to_background(mask);
    let distance_width = if skeleton_px == 0 {
        0.0
    } else {
        skel.pixels
            .iter()
            .zip(&dist2)
            .filter(|(s, _)| **s)
            .map(|(_, d2)| 2.0 * d2.sqrt() - 1.0)
            .sum::<f64>()
            / skeleton_px as f64
    };
    MaskMeasure {
        image_width_px: mask.width,
        image_height_px: mask.height,
        area_px: area,
        skeleton_px,
        skeleton_length_px: length,
        width_px: if length > 0.0 {
            area as f64 / length
        } else {
            0.0
        },
        distance_width_px: distance_width,
    }
}

/// Eq. 1 over a set of masks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CrackLengthEstimate {
    /// Masks given.
    pub masks: usize,
    /// Masks holding at least one crack pixel: eq. 1's `N_c` (empty masks are left out).
    pub n_c: usize,
    /// Mean crack pixels per image, `Ā` (over the `N_c` images).
    pub mean_area_px: f64,
    /// Mean pixels per image (over the `N_c` images).
    pub mean_image_px: f64,
    /// Mean image height, pixels (over the `N_c` images).
    pub mean_image_height_px: f64,
    /// `w̄ = mean A_i / S_i`, pixels: the width eq. 1 divides by.
    pub mean_width_px: f64,
    /// The distance-transform width, for comparison, pixels.
    pub mean_distance_width_px: f64,
    /// `L̄ = mean A_i / w̄`, pixels.
    pub mean_length_px: f64,
    /// Mean centre-line length `mean S_i`, pixels (what eq. 1 approximates).
    pub mean_skeleton_length_px: f64,
    /// Mean of `L_i / H_i` (`H_i` the image's height): the crack length as a fraction of the
    /// image height, what the planner maps onto the workspace
    /// ([`CrackLengthEstimate::mean_length_mm`]).
    pub mean_length_fraction_of_height: f64,
    /// Every mask that holds a crack, in the order given.
    pub per_image: Vec<MaskMeasure>,
}

impl CrackLengthEstimate {
    /// `L̄` in millimetres on a workspace `height_mm` tall: the crack length as a fraction of
    /// its image's height, applied to the workspace height (see the crate docs, "Pixels to
    /// millimetres").
    pub fn mean_length_mm(&self, height_mm: f64) -> f64 {
        self.mean_length_fraction_of_height * height_mm
    }
}

/// Eq. 1 over `masks`: `w̄` and `L̄` measured as the module docs say. Masks without a crack pixel
/// are counted in [`CrackLengthEstimate::masks`] but not in `N_c`. Errors when no mask holds a
/// crack.
pub fn mean_crack_length(
    masks: impl IntoIterator<Item = BinaryMask>,
) -> Result<CrackLengthEstimate, PlanError> {
    let mut total = 0;
    let mut per_image = Vec::new();
    for mask in masks {
        total += 1;
        let m = measure_mask(&mask);
        if m.area_px > 0 {
            per_image.push(m);
        }
    }
    estimate_from_measures(total, per_image)
}

/// Eq. 1 from per-mask measures (`masks`: how many masks they came from, empty ones included).
pub fn estimate_from_measures(
    masks: usize,
    per_image: Vec<MaskMeasure>,
) -> Result<CrackLengthEstimate, PlanError> {
    let per_image: Vec<MaskMeasure> = per_image.into_iter().filter(|m| m.area_px > 0).collect();
    if per_image.is_empty() {
        return Err(PlanError::NoCracks { masks });
    }
    let n = per_image.len() as f64;
    let mean = |f: &dyn Fn(&MaskMeasure) -> f64| per_image.iter().map(f).sum::<f64>() / n;
    let w_bar = mean(&|m| m.width_px);
    let l_bar = mean(&|m| m.area_px as f64 / w_bar);
    Ok(CrackLengthEstimate {
        masks,
        n_c: per_image.len(),
        mean_area_px: mean(&|m| m.area_px as f64),
        mean_image_px: mean(&|m| (m.image_width_px * m.image_height_px) as f64),
        mean_image_height_px: mean(&|m| m.image_height_px as f64),
        mean_width_px: w_bar,
        mean_distance_width_px: mean(&|m| m.distance_width_px),
        mean_length_px: l_bar,
        mean_skeleton_length_px: mean(&|m| m.skeleton_length_px),
        mean_length_fraction_of_height: mean(&|m| {
            m.area_px as f64 / w_bar / m.image_height_px as f64
        }),
        per_image,
    })
}

/// Eq. 1 with a given width: `L_i = A_i / w̄` for each area, and their mean `L̄`.
pub fn eq1(areas_px: &[f64], mean_width_px: f64) -> (Vec<f64>, f64) {
    let l: Vec<f64> = areas_px.iter().map(|a| a / mean_width_px).collect();
    let mean = l.iter().sum::<f64>() / l.len().max(1) as f64;
    (l, mean)
}

/// The eight neighbours of `(x, y)`, counter-clockwise from east: E, NE, N, NW, W, SW, S, SE.
fn neighbours(m: &BinaryMask, x: isize, y: isize) -> [bool; 8] {
    thinning::neighbours(&m.pixels, m.width, x, y)
}

/// The mask thinned to one-pixel centre lines ([`crackbot_imaging::thinning::thin`], see the
/// module docs).
pub fn skeleton(mask: &BinaryMask) -> BinaryMask {
    let mut s = mask.clone();
    thinning::thin(&mut s.pixels, s.width);
    s
}

/// Length of a one-pixel centre line, pixels (see the module docs).
pub fn skeleton_length(s: &BinaryMask) -> f64 {
    let mut length = 0.0;
    for y in 0..s.height as isize {
        for x in 0..s.width as isize {
            if !s.get(x, y) {
                continue;
            }
            let (e, south, w) = (s.get(x + 1, y), s.get(x, y + 1), s.get(x - 1, y));
            length += f64::from(u8::from(e)) + f64::from(u8::from(south));
            if s.get(x + 1, y + 1) && !e && !south {
                length += std::f64::consts::SQRT_2;
            }
            if s.get(x - 1, y + 1) && !w && !south {
                length += std::f64::consts::SQRT_2;
            }
            let degree = neighbours(s, x, y).iter().filter(|&&v| v).count();
            length += match degree {
                0 => 1.0,
                1 => 0.5,
                _ => 0.0,
            };
        }
    }
    length
}

/// Squared Euclidean distance from every pixel to the nearest non-crack pixel (pixels outside
/// the image count as non-crack), row-major; 0 on non-crack pixels. Felzenszwalb and
/// Huttenlocher's two-pass lower envelope of parabolas.
pub fn distance_squared_to_background(mask: &BinaryMask) -> Vec<f64> {
    // Pad by one non-crack pixel on every side.
    let (w, h) = (mask.width + 2, mask.height + 2);
    // Larger than any squared distance in the image, small enough to keep the arithmetic exact.
    let inf = 2.0 * ((w * w + h * h) as f64) + 1.0;
    let mut f = vec![0.0; w * h];
    for y in 0..mask.height {
        for x in 0..mask.width {
            if mask.pixels[y * mask.width + x] {
                f[(y + 1) * w + x + 1] = inf;
            }
        }
    }
    let mut buf = vec![0.0; w.max(h)];
    let mut out = vec![0.0; w.max(h)];
    // Columns, then rows.
    for x in 0..w {
        for y in 0..h {
            buf[y] = f[y * w + x];
        }
        edt_1d(&buf[..h], &mut out[..h]);
        for y in 0..h {
            f[y * w + x] = out[y];
        }
    }
    for y in 0..h {
        buf[..w].copy_from_slice(&f[y * w..(y + 1) * w]);
        edt_1d(&buf[..w], &mut out[..w]);
        f[y * w..(y + 1) * w].copy_from_slice(&out[..w]);
    }
    let mut d = Vec::with_capacity(mask.width * mask.height);
    for y in 0..mask.height {
        d.extend_from_slice(&f[(y + 1) * w + 1..(y + 1) * w + 1 + mask.width]);
    }
    d
}

fn edt_1d(f: &[f64], d: &mut [f64]) {
    let n = f.len();
    let mut v = vec![0usize; n];
    let mut z = vec![0.0f64; n + 1];
    let meet = |q: usize, p: usize| {
        ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    let mut k = 0usize;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let mut s = meet(q, v[k]);
        while s <= z[k] {
            // z[0] is -inf, so k never goes below 0.
            k -= 1;
            s = meet(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, out) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let p = v[k];
        *out = (q as f64 - p as f64).powi(2) + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(w: usize, h: usize, thick: usize) -> BinaryMask {
        // A horizontal band `thick` pixels tall across the middle, 10 px from each side.
        let y0 = h / 2 - thick / 2;
        BinaryMask::from_fn(w, h, |x, y| {
            (10..w - 10).contains(&x) && (y0..y0 + thick).contains(&y)
        })
        .unwrap()
    }

    #[test]
    fn a_straight_band_measures_its_length_and_width() {
        for thick in [1, 2, 3, 5, 9] {
            let m = measure_mask(&line(120, 40, thick));
            assert_eq!(m.area_px, 100 * thick);
            // Thinning eats the ends of a thick band by up to half its thickness.
            assert!(
                (m.skeleton_length_px - 100.0).abs() <= thick as f64 / 2.0 + 1.0,
                "{thick}: {m:?}"
            );
            assert!(
                (m.width_px - thick as f64).abs() <= 0.1 * thick as f64 + 0.1,
                "{thick}: {m:?}"
            );
            // Odd bands: the distance width is exact on the centre line.
            if thick % 2 == 1 {
                assert!(
                    (m.distance_width_px - thick as f64).abs() < 0.3,
                    "{thick}: {m:?}"
                );
            }
        }
    }

    #[test]
    fn a_diagonal_line_is_sqrt2_per_step() {
        let m = BinaryMask::from_fn(60, 60, |x, y| x == y && (5..55).contains(&x)).unwrap();
        let s = skeleton(&m);
        assert_eq!(s, m, "a one-pixel line is its own skeleton");
        let len = skeleton_length(&s);
        assert!(
            (len - (49.0 * std::f64::consts::SQRT_2 + 1.0)).abs() < 1e-9,
            "{len}"
        );
        // A thick diagonal band: width across it about 5 / √2 · √2 …
        let band = BinaryMask::from_fn(80, 80, |x, y| {
            (x as f64 - y as f64).abs() <= 3.0 && (10..70).contains(&x)
        })
        .unwrap();
        let m = measure_mask(&band);
        let true_len = 60.0 * std::f64::consts::SQRT_2;
        assert!((m.skeleton_length_px - true_len).abs() < 8.0, "{m:?}");
        // The band is 7 pixels wide along x, 7/√2 ≈ 4.95 across.
        assert!(
            (m.width_px - 7.0 / std::f64::consts::SQRT_2).abs() < 0.8,
            "{m:?}"
        );
    }

    #[test]
    fn small_blobs_and_rings_keep_their_topology() {
        // A 2×2 square (which plain Zhang–Suen deletes) keeps a pixel.
        let sq =
            BinaryMask::from_fn(6, 6, |x, y| (2..4).contains(&x) && (2..4).contains(&y)).unwrap();
        assert!(skeleton(&sq).crack_pixels() >= 1);
        assert!(measure_mask(&sq).width_px > 0.0);
        // A lone pixel: length 1, width 1.
        let p = BinaryMask::from_fn(5, 5, |x, y| x == 2 && y == 2).unwrap();
        let m = measure_mask(&p);
        assert_eq!(
            (m.skeleton_length_px, m.width_px, m.distance_width_px),
            (1.0, 1.0, 1.0)
        );
        // A thick ring stays a ring (a loop of centre line).
        let ring = BinaryMask::from_fn(60, 60, |x, y| {
            let r = ((x as f64 - 30.0).powi(2) + (y as f64 - 30.0).powi(2)).sqrt();
            (15.0..20.0).contains(&r)
        })
        .unwrap();
        let m = measure_mask(&ring);
        let circumference = std::f64::consts::TAU * 17.5;
        assert!(
            (m.skeleton_length_px / circumference - 1.0).abs() < 0.1,
            "{m:?}"
        );
        // A crack touching the border: the outside is not crack.
        let edge = BinaryMask::from_fn(10, 10, |_, y| y == 0).unwrap();
        assert_eq!(measure_mask(&edge).distance_width_px, 1.0);
    }

    #[test]
    fn eq1_reproduces_the_papers_figure() {
        let (_, l) = eq1(&[PAPER_EQ1.mean_area_px], PAPER_EQ1.mean_width_px);
        assert!((l - 148.05).abs() < 1e-9);
        // The paper prints 148.06: its Ā is rounded.
        assert!((l - PAPER_EQ1.mean_length_px).abs() < 0.02);
    }

    #[test]
    fn eq1_over_masks_and_its_errors() {
        let masks = vec![
            line(120, 40, 3),
            line(120, 40, 1),
            BinaryMask::from_fn(4, 4, |_, _| false).unwrap(),
        ];
        let e = mean_crack_length(masks).unwrap();
        assert_eq!((e.masks, e.n_c), (3, 2));
        assert!((e.mean_area_px - 200.0).abs() < 1e-9);
        assert!((e.mean_width_px - 2.0).abs() < 0.2, "{e:?}");
        assert!((e.mean_length_px - 100.0).abs() < 10.0, "{e:?}");
        assert!((e.mean_length_fraction_of_height - e.mean_length_px / 40.0).abs() < 1e-9);
        let empty = mean_crack_length(vec![BinaryMask::from_fn(3, 3, |_, _| false).unwrap()]);
        assert_eq!(empty.unwrap_err(), PlanError::NoCracks { masks: 1 });
        assert!(matches!(
            mean_crack_length(Vec::new()),
            Err(PlanError::NoCracks { masks: 0 })
        ));
        assert!(BinaryMask::new(0, 3, vec![]).is_err());
        assert!(BinaryMask::new(2, 3, vec![true; 5])
            .unwrap_err()
            .to_string()
            .contains("5 pixels"));
    }

    #[test]
    fn distance_transform_matches_brute_force() {
        let m = BinaryMask::from_fn(23, 17, |x, y| (x * 7 + y * 3) % 5 != 0 || (x > 8 && x < 15))
            .unwrap();
        let d = distance_squared_to_background(&m);
        for y in 0..17isize {
            for x in 0..23isize {
                let mut best = f64::INFINITY;
                for yy in -1..=17isize {
                    for xx in -1..=23isize {
                        if !m.get(xx, yy) {
                            best = best.min(((xx - x).pow(2) + (yy - y).pow(2)) as f64);
                        }
                    }
                }
                assert_eq!(d[(y * 23 + x) as usize], best, "({x}, {y})");
            }
        }
    }
}
