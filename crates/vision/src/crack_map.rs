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
//!    the image are dropped;
//! 5. the score is the highest probability of the component's crack cells (on the training split
//!    it ranks components better than their mean: `models/detector/analysis/scoring.py`);
//!    detections are sorted by score (ties keep component order) and at most `max_detections`
//!    are kept.
//!
//! `models/detector/seg_post.py` is the independent (numpy + scipy) implementation of the same
//! rule; `tests/onnx_reference.rs` checks the two agree on real photos.

use serde::{Deserialize, Serialize};

use crate::boxes::{BoundingBox, Detection};
use crate::preprocess::{Letterbox, PostprocessParams};
use crate::VisionError;

/// Canvas pixels per map cell, along each axis.
pub const MAP_STRIDE: usize = 2;
/// A cell at or above this probability is a crack cell.
pub const MAP_THRESHOLD: f32 = 0.5;
/// The dilation radius, as a fraction of the image's longer side (the dataset rule's 0.02).
pub const DILATION_FRACTION: f32 = 0.02;
/// Boxes smaller than this fraction of the image are dropped (the dataset rule's 0.1%).
pub const MIN_AREA_FRACTION: f32 = 0.001;
/// Most points of a crack's centre-line polyline.
pub const MAX_POLYLINE_POINTS: usize = 9;

/// Where a detected crack runs, in image pixels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrackShape {
    /// The main axis: the two ends of the crack along its principal direction.
    pub axis: [[f32; 2]; 2],
    /// The centre line from one end to the other (2 to [`MAX_POLYLINE_POINTS`] points).
    pub polyline: Vec<[f32; 2]>,
    /// Length of the polyline, pixels.
    pub length_px: f32,
}

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
    let min_area = MIN_AREA_FRACTION * w * h;
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
            let score = c.max;
            (bbox.area() >= min_area && score >= params.score_threshold).then(|| Detection {
                bbox,
                score,
                shape: Some(c.shape(to_img)),
            })
        })
        .collect();
    dets.sort_by(|a, b| b.score.total_cmp(&a.score));
    dets.truncate(params.max_detections);
    dets
}

/// Crack cells of one component.
#[derive(Default)]
struct Component {
    cells: Vec<(usize, usize, f32)>,
    max: f32,
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
        self.max = self.max.max(p);
        self.cells.push((r, c, p));
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
        }
    }
}

/// Binary dilation by a disk of radius `r` cells (offsets with `dx² + dy² ≤ r²`).
fn dilate(mask: &[bool], rows: usize, cols: usize, r: usize) -> Vec<bool> {
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
fn label_components(mask: &[bool], rows: usize, cols: usize) -> Vec<u32> {
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
        assert!((d.score - 0.9).abs() < 1e-6);
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
        assert!((dets[0].score - 0.8).abs() < 1e-6, "{dets:?}");
        assert!((dets[1].score - 0.7).abs() < 1e-6);
        let joined = &dets[0];
        assert_eq!((joined.bbox.x0, joined.bbox.x1), (40.0, 220.0));
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
