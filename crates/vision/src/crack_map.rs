//! From a crack map to crack detections: the boxes by the crack datasets' own rule, and each
//! crack's main axis and centre-line polyline for the planner.
//!
//! The segmentation detector (`models/detector/MODEL_CARD.md`, "Crack map") returns, for an
//! `S × S` letterboxed input, a map of `S/2 × S/2` cells: the probability that the 2×2 canvas
//! pixels of the cell hold a crack. [`map_detections`] turns it into detections the way
//! `../shared/data/cracks/README.md` ("How the boxes were made") turns a mask into boxes:
//! 1. cells outside the letterboxed image are ignored; a cell is *crack* when its probability is
//!    at least [`MAP_THRESHOLD`];
//! 2. the crack cells are dilated by a disk of radius `round(0.02 · max(W, H))` image pixels
//!    (in cells: `max(1, round(r · s / 2))`), which joins the pieces of one broken crack;
//! 3. 8-connected components of the dilated map, numbered in raster order of their first cell;
//! 4. each component's box is the tight box of its *undilated* crack cells, in image pixels
//!    (`x0 = 2·c_min / s`, `x1 = 2·(c_max + 1) / s`, clipped to the image); boxes under 0.1% of
//!    the image are dropped (`PostprocessParams::min_area_fraction`);
//! 5. the score is `0.5 + 0.5 · m · min(1, d / (0.5 · max(W, H)))^0.5`, with `m` the mean
//!    probability of the component's crack cells and `d` its box's diagonal in image pixels
//!    ([`component_score`]): long, confident cracks first. It ranks the photos' components better
//!    than the cells' highest probability did (chosen on the photos' training split:
//!    `models/detector/analysis/linking.py`) and stays in `[0.5, 1]`, so any threshold below 0.5
//!    keeps every component; detections are sorted by score (ties keep component order) and at
//!    most `max_detections` are kept.
//!
//! `models/detector/contract.py` is the independent (numpy + scipy) implementation of the same
//! rule; `crates/vision/tests/onnx_reference.rs` checks the two agree on real photos.
//!
//! **Where to touch** ([`CrackShape::pieces`]). The dilation that joins a broken crack also joins
//! cracks that run close together or cross, and a component's main axis then passes between
//! them. For the finger, each component is split into the cracks it holds: its crack cells are
//! thinned to a centre line ([`crackbot_imaging::thinning`]), the line is cut at its junctions
//! into branches and at its sharp corners (two cracks meeting in a V, [`CORNER_DEG`]), spurs
//! shorter than [`SPUR_CELLS`] are dropped, two junctions joined by a branch no longer than
//! [`BRIDGE_CELLS`] are one crossing (lines crossing at a slant thin to two), and branches are
//! joined again where a crack plainly goes on: through a junction the pair of branches that
//! continue each other best (within [`CONTINUATION_DEG`] of straight), and across a gap no
//! longer than the dilation joins when both ends point at each other and turn no more than
//! through a junction (two cracks meeting in a V across a gap stay two pieces). Each joined run
//! is a [`CrackPiece`]: a centre-line point near its middle and away from junctions (where a
//! stroke across meets that crack alone), its local direction and its length.

use crate::boxes::{BoundingBox, Detection};
use crate::preprocess::{Letterbox, PostprocessParams};
use crate::VisionError;

mod centre_line;
use centre_line::pieces;

pub use crate::preprocess::MIN_AREA_FRACTION;
pub use crate::shape::{CrackPiece, CrackShape, MAX_POLYLINE_POINTS};
pub use centre_line::{BRIDGE_CELLS, CONTINUATION_DEG, CORNER_DEG, MIN_PIECE_CELLS, SPUR_CELLS};

/// Canvas pixels per map cell, along each axis.
pub const MAP_STRIDE: usize = 2;
/// A cell at or above this probability is a crack cell.
pub const MAP_THRESHOLD: f32 = 0.5;
/// The dilation radius, as a fraction of the image's longer side (the dataset rule's 0.02).
pub const DILATION_FRACTION: f32 = 0.02;

/// A crack map of one letterboxed frame: `cells × cells` probabilities, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackMap {
    cells: usize,
    prob: Vec<f32>,
    letterbox: Letterbox,
}

impl CrackMap {
    /// The map the model returned for the frame letterboxed as `letterbox`. Errors when the
    /// number of values is not `(S/2)²` or a value is not a probability.
    pub fn new(prob: Vec<f32>, letterbox: Letterbox) -> Result<Self, VisionError> {
        let cells = letterbox.size / MAP_STRIDE;
        if prob.len() != cells * cells || cells == 0 {
            return Err(VisionError::Runtime(format!(
                "crack map has {} values, expected {cells}×{cells} for a {} input",
                prob.len(),
                letterbox.size
            )));
        }
        if let Some((i, v)) = prob
            .iter()
            .enumerate()
            .find(|(_, v)| !(v.is_finite() && (0.0..=1.0).contains(*v)))
        {
            return Err(VisionError::Runtime(format!(
                "crack map value {v} at cell {i} is not a probability in [0, 1]"
            )));
        }
        Ok(Self {
            cells,
            prob,
            letterbox,
        })
    }

    /// Cells per side.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// The probabilities, row-major.
    pub fn probabilities(&self) -> &[f32] {
        &self.prob
    }

    /// The letterbox of the frame.
    pub fn letterbox(&self) -> &Letterbox {
        &self.letterbox
    }

    /// Rows and columns of cells that overlap the letterboxed image.
    fn valid(&self) -> (usize, usize) {
        let lb = &self.letterbox;
        (
            lb.height.div_ceil(MAP_STRIDE).min(self.cells),
            lb.width.div_ceil(MAP_STRIDE).min(self.cells),
        )
    }

    /// The map at the image's resolution (each pixel takes the cell under its centre), row-major
    /// `W × H`.
    pub fn to_image(&self) -> Vec<f32> {
        let lb = &self.letterbox;
        let (w, h) = (lb.image_width as usize, lb.image_height as usize);
        let cell = |i: usize| {
            (((i as f32 + 0.5) * lb.scale / MAP_STRIDE as f32).floor() as usize).min(self.cells - 1)
        };
        let cols: Vec<usize> = (0..w).map(cell).collect();
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            let row = &self.prob[cell(y) * self.cells..][..self.cells];
            out.extend(cols.iter().map(|&c| row[c]));
        }
        out
    }
}

/// The dilation radius in cells for the map's image.
pub fn dilation_radius_cells(lb: &Letterbox) -> usize {
    let r_img = (DILATION_FRACTION * lb.image_width.max(lb.image_height) as f32 + 0.5).floor();
    ((r_img * lb.scale / MAP_STRIDE as f32 + 0.5).floor() as usize).max(1)
}

/// Detections from a crack map, by the dataset rule of the [module docs](self): boxes, scores
/// and each crack's [`CrackShape`]. Components scoring below `params.score_threshold` are
/// dropped; `params.iou_threshold` is not used (components never overlap in the map).
pub fn map_detections(map: &CrackMap, params: &PostprocessParams) -> Vec<Detection> {
    let (rows, cols) = map.valid();
    let n = map.cells;
    let crack: Vec<bool> = (0..rows * cols)
        .map(|i| map.prob[(i / cols) * n + i % cols] >= MAP_THRESHOLD)
        .collect();
    if !crack.iter().any(|&c| c) {
        return Vec::new();
    }
    let dilated = dilate(&crack, rows, cols, dilation_radius_cells(&map.letterbox));
    let labels = label_components(&dilated, rows, cols);
    let lb = &map.letterbox;
    let (w, h) = (lb.image_width as f32, lb.image_height as f32);
    let to_img = MAP_STRIDE as f32 / lb.scale;
    let mut comps: Vec<Component> = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            if !crack[i] {
                continue;
            }
            let k = labels[i] as usize - 1;
            if comps.len() <= k {
                comps.resize_with(k + 1, Component::default);
            }
            comps[k].add(r, c, map.prob[r * n + c]);
        }
    }
    let min_area = params.min_area_fraction * w * h;
    let mut dets: Vec<Detection> = comps
        .iter()
        .filter(|c| !c.cells.is_empty())
        .filter_map(|c| {
            let bbox = BoundingBox {
                x0: (c.c0 as f32 * to_img).min(w),
                y0: (c.r0 as f32 * to_img).min(h),
                x1: ((c.c1 + 1) as f32 * to_img).min(w),
                y1: ((c.r1 + 1) as f32 * to_img).min(h),
            };
            let score = component_score(c.mean(), bbox.diagonal(), w, h);
            (bbox.area() >= min_area && score >= params.score_threshold).then(|| {
                let mut shape = c.shape(to_img);
                let cells: Vec<(usize, usize)> = c.cells.iter().map(|&(r, c, _)| (r, c)).collect();
                shape.pieces = pieces(&cells, 2 * dilation_radius_cells(lb) + 1, to_img);
                Detection {
                    bbox,
                    score,
                    shape: Some(shape),
                    source: crate::DetectionSource::Primary,
                }
            })
        })
        .collect();
    dets.sort_by(|a, b| b.score.total_cmp(&a.score));
    dets.truncate(params.max_detections);
    dets
}

/// A box diagonal of at least this fraction of the image's longer side ranks in full
/// ([`component_score`]).
pub const FULL_LENGTH_FRACTION: f32 = 0.5;

/// A component's score from the mean probability of its crack cells and its box's diagonal
/// (image pixels) in a `w × h` image: `0.5 + 0.5 · mean · min(1, diagonal / (0.5 · max(w, h)))^0.5`,
/// in `[0.5, 1]` for a mean in `[0, 1]` (step 5 of the [module docs](self)).
pub fn component_score(mean: f32, diagonal: f32, w: f32, h: f32) -> f32 {
    let full = FULL_LENGTH_FRACTION * w.max(h);
    let length = if full > 0.0 {
        (diagonal / full).min(1.0)
    } else {
        1.0
    };
    0.5 + 0.5 * mean * length.max(0.0).sqrt()
}

/// Crack cells of one component.
#[derive(Default)]
struct Component {
    cells: Vec<(usize, usize, f32)>,
    sum: f64,
    r0: usize,
    r1: usize,
    c0: usize,
    c1: usize,
}

impl Component {
    fn add(&mut self, r: usize, c: usize, p: f32) {
        if self.cells.is_empty() {
            (self.r0, self.r1, self.c0, self.c1) = (r, r, c, c);
        }
        self.r0 = self.r0.min(r);
        self.r1 = self.r1.max(r);
        self.c0 = self.c0.min(c);
        self.c1 = self.c1.max(c);
        self.sum += f64::from(p);
        self.cells.push((r, c, p));
    }

    /// The mean probability of the crack cells.
    fn mean(&self) -> f32 {
        (self.sum / self.cells.len().max(1) as f64) as f32
    }

    /// Main axis (probability-weighted principal direction of the cell centres) and the centre
    /// line: the weighted mean of the cells in equal bins along the axis.
    fn shape(&self, to_img: f32) -> CrackShape {
        let pts: Vec<([f64; 2], f64)> = self
            .cells
            .iter()
            .map(|&(r, c, p)| {
                let s = f64::from(to_img);
                ([(c as f64 + 0.5) * s, (r as f64 + 0.5) * s], f64::from(p))
            })
            .collect();
        let wsum: f64 = pts.iter().map(|(_, w)| w).sum::<f64>().max(1e-12);
        let mx = pts.iter().map(|(p, w)| p[0] * w).sum::<f64>() / wsum;
        let my = pts.iter().map(|(p, w)| p[1] * w).sum::<f64>() / wsum;
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for (p, w) in &pts {
            let (dx, dy) = (p[0] - mx, p[1] - my);
            sxx += w * dx * dx;
            sxy += w * dx * dy;
            syy += w * dy * dy;
        }
        // Principal direction of the 2×2 covariance (angle of the major axis).
        let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (ux, uy) = (theta.cos(), theta.sin());
        let proj = |p: &[f64; 2]| (p[0] - mx) * ux + (p[1] - my) * uy;
        let (mut t0, mut t1) = (f64::INFINITY, f64::NEG_INFINITY);
        for (p, _) in &pts {
            let t = proj(p);
            t0 = t0.min(t);
            t1 = t1.max(t);
        }
        let at = |t: f64| [(mx + t * ux) as f32, (my + t * uy) as f32];
        let axis = [at(t0), at(t1)];
        let span = t1 - t0;
        let bins =
            ((span / (4.0 * f64::from(to_img))).round() as usize).clamp(1, MAX_POLYLINE_POINTS);
        let mut acc = vec![(0.0f64, 0.0f64, 0.0f64); bins];
        for (p, w) in &pts {
            let b = (((proj(p) - t0) / span.max(1e-12)) * bins as f64).floor() as usize;
            let a = &mut acc[b.min(bins - 1)];
            a.0 += p[0] * w;
            a.1 += p[1] * w;
            a.2 += w;
        }
        let mut polyline: Vec<[f32; 2]> = acc
            .iter()
            .filter(|a| a.2 > 0.0)
            .map(|a| [(a.0 / a.2) as f32, (a.1 / a.2) as f32])
            .collect();
        if polyline.len() < 2 {
            polyline = axis.to_vec();
        }
        let length_px = polyline
            .windows(2)
            .map(|s| (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]))
            .sum();
        CrackShape {
            axis,
            polyline,
            length_px,
            pieces: Vec::new(),
        }
    }
}

/// Binary dilation by a disk of radius `r` cells (offsets with `dx² + dy² ≤ r²`).
pub(crate) fn dilate(mask: &[bool], rows: usize, cols: usize, r: usize) -> Vec<bool> {
    let r = r as isize;
    let offsets: Vec<(isize, isize)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dy, dx)))
        .filter(|(dy, dx)| dx * dx + dy * dy <= r * r)
        .collect();
    let mut out = vec![false; mask.len()];
    for y in 0..rows {
        for x in 0..cols {
            if !mask[y * cols + x] {
                continue;
            }
            for &(dy, dx) in &offsets {
                let (yy, xx) = (y as isize + dy, x as isize + dx);
                if yy >= 0 && xx >= 0 && (yy as usize) < rows && (xx as usize) < cols {
                    out[yy as usize * cols + xx as usize] = true;
                }
            }
        }
    }
    out
}

/// 8-connected components, labelled `1..` in raster order of their first cell (0: background).
pub(crate) fn label_components(mask: &[bool], rows: usize, cols: usize) -> Vec<u32> {
    let mut labels = vec![0u32; mask.len()];
    let mut next = 0u32;
    let mut stack = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || labels[start] != 0 {
            continue;
        }
        next += 1;
        labels[start] = next;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let (y, x) = ((i / cols) as isize, (i % cols) as isize);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (yy, xx) = (y + dy, x + dx);
                    if yy < 0 || xx < 0 || yy as usize >= rows || xx as usize >= cols {
                        continue;
                    }
                    let j = yy as usize * cols + xx as usize;
                    if mask[j] && labels[j] == 0 {
                        labels[j] = next;
                        stack.push(j);
                    }
                }
            }
        }
    }
    labels
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map_with(size: usize, w: u32, h: u32, cells: &[(usize, usize, f32)]) -> CrackMap {
        let n = size / MAP_STRIDE;
        let mut prob = vec![0.0; n * n];
        for &(r, c, p) in cells {
            prob[r * n + c] = p;
        }
        CrackMap::new(prob, Letterbox::new(w, h, size).unwrap()).unwrap()
    }

    fn params() -> PostprocessParams {
        PostprocessParams {
            score_threshold: 0.001,
            ..PostprocessParams::default()
        }
    }

    #[test]
    fn a_diagonal_crack_gives_one_box_its_axis_and_a_polyline_along_it() {
        // 320 input, 640×640 image: s = 0.5, one cell = 4 image px.
        let cells: Vec<_> = (10..60).map(|i| (i, i + 5, 0.9)).collect();
        let dets = map_detections(&map_with(320, 640, 640, &cells), &params());
        assert_eq!(dets.len(), 1);
        let d = &dets[0];
        assert_eq!(
            d.bbox,
            BoundingBox {
                x0: 60.0,
                y0: 40.0,
                x1: 260.0,
                y1: 240.0
            }
        );
        // Mean 0.9, a 200 × 200 px box against a full length of 320 px.
        let expected = 0.5 + 0.5 * 0.9 * (200.0 * 2f32.sqrt() / 320.0).sqrt();
        assert!(
            (d.score - expected).abs() < 1e-6,
            "{} against {expected}",
            d.score
        );
        let shape = d.shape.as_ref().unwrap();
        // The axis runs from the first to the last cell centre, along the diagonal.
        let [a, b] = shape.axis;
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        assert!((dx.abs() - dy.abs()).abs() < 1e-3, "{a:?} {b:?}");
        assert!((dx.hypot(dy) - 49.0 * 4.0 * 2f32.sqrt()).abs() < 1.0);
        assert!(shape.polyline.len() >= 2 && shape.polyline.len() <= MAX_POLYLINE_POINTS);
        for p in &shape.polyline {
            // On the line y = x − 20 (cell centres (c + 0.5)·4, (r + 0.5)·4 with c = r + 5).
            assert!((p[1] - (p[0] - 20.0)).abs() < 1e-3, "{p:?}");
        }
        assert!(shape.length_px > 0.8 * 49.0 * 4.0 * 2f32.sqrt());
    }

    #[test]
    fn pieces_closer_than_the_dilation_join_and_far_ones_do_not() {
        // 640 px image at 320: r = round(12.8) = 13 px → round(3.25) = 3 cells.
        let lb = Letterbox::new(640, 480, 320).unwrap();
        assert_eq!(dilation_radius_cells(&lb), 3);
        let mut cells: Vec<_> = (10..30).map(|c| (20, c, 0.8)).collect();
        cells.extend((35..55).map(|c| (20, c, 0.6))); // gap of 5 cells ≤ 2r: joined
        cells.extend((100..130).map(|c| (100, c, 0.7))); // far away: its own box, second
        let dets = map_detections(&map_with(320, 640, 480, &cells), &params());
        assert_eq!(dets.len(), 2);
        // The joined pair: mean 0.7 over a 180 × 4 px box; the far one: 0.7 over 120 × 4 px.
        let joined_score = component_score(0.7, 180f32.hypot(4.0), 640.0, 480.0);
        assert!((dets[0].score - joined_score).abs() < 1e-6, "{dets:?}");
        assert!(
            (dets[1].score - component_score(0.7, 120f32.hypot(4.0), 640.0, 480.0)).abs() < 1e-6
        );
        let joined = &dets[0];
        assert_eq!((joined.bbox.x0, joined.bbox.x1), (40.0, 220.0));
    }

    #[test]
    fn the_score_ranks_long_confident_cracks_first_and_stays_in_half_to_one() {
        let (w, h) = (640.0, 480.0);
        // Full length is half the longer side (320 px): beyond it only the mean counts.
        assert_eq!(component_score(0.8, 320.0, w, h), 0.9);
        assert_eq!(component_score(0.8, 900.0, w, h), 0.9);
        assert!(component_score(0.8, 40.0, w, h) < component_score(0.8, 160.0, w, h));
        assert!(component_score(0.6, 300.0, w, h) < component_score(0.9, 300.0, w, h));
        for mean in [0.0, 0.5, 0.75, 1.0] {
            for diagonal in [0.0, 1.0, 50.0, 320.0, 1e6] {
                let s = component_score(mean, diagonal, w, h);
                assert!((0.5..=1.0).contains(&s), "{mean} {diagonal} → {s}");
            }
        }
        // Every component passes a threshold under 0.5, as with the cells' highest probability.
        assert!(component_score(0.5, 0.0, w, h) >= 0.5);
    }

    #[test]
    fn a_thin_crack_along_a_pixel_row_is_dropped_by_the_dataset_rule_and_kept_without_it() {
        // 640 × 480 at 320 (one cell = 4 image px): a crack 8 cells (32 px) long and one cell
        // thick has a 32 × 4 px box, 128 px² against the rule's 307 px².
        let cells: Vec<_> = (40..48).map(|c| (30, c, 0.9)).collect();
        let map = map_with(320, 640, 480, &cells);
        assert!(map_detections(&map, &params()).is_empty());
        let keep_all = PostprocessParams {
            min_area_fraction: 0.0,
            ..params()
        };
        let dets = map_detections(&map, &keep_all);
        assert_eq!(dets.len(), 1);
        let shape = dets[0].shape.as_ref().unwrap();
        assert_eq!(shape.pieces.len(), 1, "{shape:?}");
        // A speck of two cells has no centre line long enough to touch.
        let speck = map_with(320, 640, 480, &[(30, 40, 0.9), (30, 41, 0.9)]);
        let dets = map_detections(&speck, &keep_all);
        assert_eq!(dets.len(), 1);
        assert!(dets[0].shape.as_ref().unwrap().pieces.is_empty());
    }

    /// Cells of a line from `a` to `b` (row, column), `thick` cells thick across it.
    fn line_cells(a: (f64, f64), b: (f64, f64), thick: usize) -> Vec<(usize, usize)> {
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()) * 2.0) as usize + 1;
        let mut out = Vec::new();
        for k in 0..=n {
            let t = k as f64 / n as f64;
            let (r, c) = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            for o in 0..thick {
                // Thick across the line's dominant direction.
                let cell = if (b.1 - a.1).abs() >= (b.0 - a.0).abs() {
                    ((r.round() as usize) + o, c.round() as usize)
                } else {
                    (r.round() as usize, (c.round() as usize) + o)
                };
                if !out.contains(&cell) {
                    out.push(cell);
                }
            }
        }
        out
    }

    /// Angle of a piece's axis from +x in the image, degrees in [0, 180).
    fn axis_deg(p: &CrackPiece) -> f64 {
        let [a, b] = p.axis;
        f64::from((b[1] - a[1]).atan2(b[0] - a[0]))
            .to_degrees()
            .rem_euclid(180.0)
    }

    #[test]
    fn a_straight_crack_is_one_piece_touched_on_its_line() {
        let cells = line_cells((20.0, 10.0), (20.0, 60.0), 2);
        let p = pieces(&cells, 7, 4.0);
        assert_eq!(p.len(), 1, "{p:?}");
        // Touched near the middle, on the two-cell-thick line (rows 20–21 → y 82–86 px).
        assert!((p[0].touch[0] - 142.0).abs() <= 12.0, "{p:?}");
        assert!((82.0..=86.0).contains(&p[0].touch[1]), "{p:?}");
        let a = axis_deg(&p[0]);
        assert!(!(5.0..=175.0).contains(&a), "{a}");
        assert!((p[0].length_px - 50.0 * 4.0).abs() < 20.0, "{p:?}");
        // Two cells thick: 8 px.
        assert!((p[0].width_px - 8.0).abs() <= 2.0, "{p:?}");
        let wide = pieces(&line_cells((20.0, 10.0), (20.0, 60.0), 6), 7, 4.0);
        assert_eq!(wide.len(), 1, "{wide:?}");
        assert!((wide[0].width_px - 24.0).abs() <= 4.0, "{wide:?}");
    }

    #[test]
    fn two_cracks_meeting_in_a_v_are_two_pieces_and_a_bent_crack_stays_one() {
        // A V: down-right for 20 cells, then up-right for 20 (a 90° corner at (40, 30)).
        let mut cells = line_cells((20.0, 10.0), (40.0, 30.0), 1);
        cells.extend(line_cells((40.0, 30.0), (20.0, 50.0), 1));
        cells.dedup();
        let p = pieces(&cells, 7, 1.0);
        assert_eq!(p.len(), 2, "{p:?}");
        let mut dirs: Vec<f64> = p.iter().map(axis_deg).collect();
        dirs.sort_by(f64::total_cmp);
        assert!(
            (dirs[0] - 45.0).abs() < 10.0 && (dirs[1] - 135.0).abs() < 10.0,
            "{dirs:?}"
        );
        // Each touched on its own arm: left of the corner and right of it.
        let mut xs: Vec<f32> = p.iter().map(|q| q.touch[0]).collect();
        xs.sort_by(f32::total_cmp);
        assert!(xs[0] < 28.0 && xs[1] > 32.0, "{xs:?}");
        // Bent by 30° (as one crack of the trial scenes bends at most): one piece.
        let mut bent = line_cells((20.0, 10.0), (20.0, 40.0), 1);
        bent.extend(line_cells((20.0, 40.0), (35.0, 66.0), 1));
        bent.dedup();
        assert_eq!(pieces(&bent, 7, 1.0).len(), 1);
    }

    #[test]
    fn two_cracks_meeting_in_a_v_across_a_gap_are_two_pieces() {
        // Trial scene 10217: two cracks whose ends face each other across a 6-cell gap, the
        // first running down-right at 35°, the second up-right at 35° (a 70° turn). Each end
        // points within 40° of the line between them, but the two do not continue each other.
        let mut cells = line_cells((16.0, 10.0), (30.0, 30.0), 1);
        cells.extend(line_cells((30.0, 36.0), (16.0, 56.0), 1));
        let p = pieces(&cells, 7, 1.0);
        assert_eq!(p.len(), 2, "{p:?}");
        let mut xs: Vec<f32> = p.iter().map(|q| q.touch[0]).collect();
        xs.sort_by(f32::total_cmp);
        assert!(xs[0] < 30.0 && xs[1] > 36.0, "{xs:?}");
        // The same gap between two pieces of one crack bent by 20°: still one piece.
        let mut bent = line_cells((20.0, 10.0), (27.0, 30.0), 1);
        bent.extend(line_cells((27.0, 36.0), (27.0, 56.0), 1));
        assert_eq!(pieces(&bent, 7, 1.0).len(), 1);
    }

    #[test]
    fn a_thin_diagonal_crack_two_cells_thick_is_a_piece_along_its_length() {
        // Two cells per row, each row one cell to the right: how a thin crack running
        // diagonally across the map looks (trial scene 10217). The thinning used to eat it from
        // its end, leaving no centre line and no piece.
        let cells: Vec<(usize, usize)> = (0..30)
            .flat_map(|k| [(10 + k, 10 + k), (10 + k, 11 + k)])
            .collect();
        let p = pieces(&cells, 7, 1.0);
        assert_eq!(p.len(), 1, "{p:?}");
        assert!(p[0].length_px > 35.0, "{p:?}");
        let a = axis_deg(&p[0]);
        assert!((a - 45.0).abs() < 10.0, "{a}");
    }

    #[test]
    fn crossing_cracks_are_two_pieces_touched_away_from_the_crossing() {
        let mut cells = line_cells((40.0, 5.0), (40.0, 75.0), 2);
        cells.extend(line_cells((5.0, 42.0), (75.0, 42.0), 2));
        let p = pieces(&cells, 7, 1.0);
        assert_eq!(p.len(), 2, "{p:?}");
        let mut angles: Vec<f64> = p.iter().map(axis_deg).collect();
        angles.sort_by(f64::total_cmp);
        assert!(angles[0] < 10.0 || angles[1] > 170.0, "{angles:?}");
        assert!(angles.iter().any(|a| (a - 90.0).abs() < 10.0), "{angles:?}");
        for q in &p {
            let d = (q.touch[0] - 42.5).hypot(q.touch[1] - 40.5);
            assert!(d >= 3.0, "touched at the crossing: {q:?}");
            assert!(q.length_px > 55.0, "{q:?}");
        }
    }

    #[test]
    fn cracks_crossing_at_a_slant_are_two_pieces() {
        // Thinned, two lines crossing at a slant meet at two junctions joined by a short
        // bridge, or one cell touching both: each line must still go on through the crossing.
        for deg in [30.0f64, 45.0, 60.0, 75.0] {
            for (t1, t2) in [(1, 1), (1, 3), (2, 2), (3, 1), (3, 3)] {
                let mut cells = line_cells((40.0, 5.0), (40.0, 85.0), t1);
                let (s, c) = deg.to_radians().sin_cos();
                let (a, b) = (
                    (40.0 - 35.0 * s, 45.0 - 35.0 * c),
                    (40.0 + 35.0 * s, 45.0 + 35.0 * c),
                );
                cells.extend(line_cells(a, b, t2));
                let p = pieces(&cells, 7, 1.0);
                assert_eq!(p.len(), 2, "{deg}° ({t1}, {t2} cells thick): {p:?}");
                // Each line is one piece, though thinning can cut one short at the crossing
                // (45°, both 2 cells thick: the upper arm of the slanted line is lost).
                assert!(
                    p.iter().all(|q| q.length_px > 30.0),
                    "{deg}° ({t1}, {t2}): {p:?}"
                );
            }
        }
    }

    #[test]
    fn a_branch_meeting_a_crack_is_its_own_piece_and_the_crack_goes_through() {
        // A long crack along row 30 and a second one meeting it from above at column 40.
        let mut cells = line_cells((30.0, 5.0), (30.0, 80.0), 2);
        cells.extend(line_cells((5.0, 40.0), (30.0, 40.0), 2));
        let p = pieces(&cells, 7, 1.0);
        assert_eq!(p.len(), 2, "{p:?}");
        assert!(
            p[0].length_px > 65.0,
            "the through crack is one piece: {p:?}"
        );
        let a = axis_deg(&p[1]);
        assert!((a - 90.0).abs() < 15.0, "{a}");
        // The branch is touched on its own line, above the crack it meets.
        assert!(p[1].touch[1] < 27.0, "{p:?}");
    }

    #[test]
    fn a_broken_crack_is_one_piece_and_parallel_cracks_are_two() {
        let mut broken = line_cells((20.0, 5.0), (20.0, 30.0), 2);
        broken.extend(line_cells((20.0, 34.0), (20.0, 60.0), 2));
        let p = pieces(&broken, 7, 1.0);
        assert_eq!(p.len(), 1, "{p:?}");
        let mut parallel = line_cells((20.0, 5.0), (20.0, 60.0), 2);
        parallel.extend(line_cells((25.0, 5.0), (25.0, 60.0), 2));
        let p = pieces(&parallel, 7, 1.0);
        assert_eq!(p.len(), 2, "{p:?}");
        // A speck is no piece: the detection keeps its main axis only.
        assert!(pieces(&[(3, 3), (3, 4)], 7, 1.0).is_empty());
        assert!(pieces(&[], 7, 1.0).is_empty());
    }

    #[test]
    fn below_threshold_tiny_and_padding_cells_give_nothing() {
        // 480×320 at 320: the image covers rows < 107 of 160 cells; row 150 is padding.
        let cells = [(150, 10, 0.99), (5, 5, 0.3), (50, 50, 0.9)];
        let dets = map_detections(&map_with(320, 480, 320, &cells), &params());
        assert!(dets.is_empty(), "{dets:?}");
    }

    #[test]
    fn bad_maps_are_errors() {
        let lb = Letterbox::new(100, 100, 32).unwrap();
        assert!(CrackMap::new(vec![0.0; 10], lb).is_err());
        let mut prob = vec![0.0; 256];
        prob[3] = f32::NAN;
        let e = CrackMap::new(prob, lb).unwrap_err().to_string();
        assert!(e.contains("cell 3"), "{e}");
        assert!(CrackMap::new(vec![1.5; 256], lb).is_err());
    }

    #[test]
    fn to_image_takes_the_cell_under_each_pixel() {
        let map = map_with(32, 64, 32, &[(0, 1, 0.75)]);
        let img = map.to_image();
        assert_eq!(img.len(), 64 * 32);
        // s = 0.5: image pixels 4..8 of row 0..4 fall in cell (0, 1).
        assert_eq!(img[4], 0.75);
        assert_eq!(img[3 * 64 + 7], 0.75);
        assert_eq!(img[8], 0.0);
        assert_eq!(img[4 * 64 + 4], 0.0);
    }
}
