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
//! 5. the score is the highest probability of the component's crack cells (on the training split
//!    it ranks components better than their mean: `models/detector/analysis/scoring.py`);
//!    detections are sorted by score (ties keep component order) and at most `max_detections`
//!    are kept.
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
    /// The cracks the component holds, longest first, where the finger should touch each (see
    /// the [module docs](self)); empty when none is at least [`MIN_PIECE_CELLS`] long.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<CrackPiece>,
}

/// One crack of a detection, where a stroke across it should go (image pixels).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrackPiece {
    /// A point of its centre line near its middle, away from junctions with other cracks.
    pub touch: [f32; 2],
    /// Its direction at `touch`: the ends of a segment through `touch`, as long as the piece.
    pub axis: [[f32; 2]; 2],
    /// Length of its centre line, pixels.
    pub length_px: f32,
    /// Its width at `touch`: the run of crack cells across its direction there, pixels (a map
    /// cell's resolution).
    pub width_px: f32,
}

/// Branches of the centre line with a free end shorter than this (map cells) are spurs.
pub const SPUR_CELLS: usize = 3;
/// A branch between two junctions at most this long (map cells) is a bridge within one crossing:
/// thinned, two lines crossing at 30–75° meet at two junctions (or one cell touching both), and
/// each line went on through neither, so a crack crossed by a print or another crack became
/// three or four pieces. On the rendered trial scenes 8000–8359 (one frame each): candidates on a
/// crack that already had one 66 → 24, other candidates 615 → 585, cracks left without a
/// candidate 30 → 35 (thick cracks side by side or crossing, merged with their neighbour); with
/// 6 cells 27, 586 and 35 (`crates/research/EXPERIMENTS.md`, "Crossings thinned to two junctions").
pub const BRIDGE_CELLS: usize = 10;
/// Pieces shorter than this (map cells) are not touched on their own.
pub const MIN_PIECE_CELLS: usize = 4;
/// Two branches continue each other through a junction (or across a gap) when their directions
/// are within this many degrees of a straight line.
pub const CONTINUATION_DEG: f64 = 40.0;
/// A centre line that turns by more than this many degrees (over [`DIRECTION_CELLS`] cells
/// either side) is two cracks meeting at a corner: one crack of the simulated trial scenes
/// bends by at most 34° at a vertex, and two pieces of one crack met at 33–38°.
pub const CORNER_DEG: f64 = 60.0;
/// Cells along a branch over which its direction at an end is taken.
const DIRECTION_CELLS: usize = 4;
/// Touch points keep at least this many cells from a junction when the piece allows.
const JUNCTION_CLEARANCE_CELLS: f64 = 3.0;

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
            let score = c.max;
            (bbox.area() >= min_area && score >= params.score_threshold).then(|| {
                let mut shape = c.shape(to_img);
                let cells: Vec<(usize, usize)> = c.cells.iter().map(|&(r, c, _)| (r, c)).collect();
                shape.pieces = pieces(&cells, 2 * dilation_radius_cells(lb) + 1, to_img);
                Detection {
                    bbox,
                    score,
                    shape: Some(shape),
                }
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
            pieces: Vec::new(),
        }
    }
}

/// Disjoint sets (union by size, path halving).
struct Sets(Vec<usize>, Vec<usize>);

impl Sets {
    fn new(n: usize) -> Self {
        Sets((0..n).collect(), vec![1; n])
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.0[i] != i {
            self.0[i] = self.0[self.0[i]];
            i = self.0[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.1[a] < self.1[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.0[b] = a;
        self.1[a] += self.1[b];
    }
}

/// One branch of the centre line: its cells in order (row, column), and at each end the
/// junction it meets (`None`: a free end).
struct Branch {
    cells: Vec<(isize, isize)>,
    junction: [Option<usize>; 2],
}

impl Branch {
    /// Unit direction pointing away from end `e` (0: first cell, 1: last) into the branch's
    /// surroundings: from a cell [`DIRECTION_CELLS`] inside towards the end.
    fn outward(&self, e: usize) -> [f64; 2] {
        let n = self.cells.len();
        let k = DIRECTION_CELLS.min(n - 1);
        let (end, inner) = if e == 0 {
            (self.cells[0], self.cells[k])
        } else {
            (self.cells[n - 1], self.cells[n - 1 - k])
        };
        let d = [(end.1 - inner.1) as f64, (end.0 - inner.0) as f64];
        let l = d[0].hypot(d[1]);
        if l > 0.0 {
            [d[0] / l, d[1] / l]
        } else {
            [0.0, 0.0]
        }
    }

    fn end(&self, e: usize) -> (isize, isize) {
        if e == 0 {
            self.cells[0]
        } else {
            self.cells[self.cells.len() - 1]
        }
    }

    /// Centre-line length, cells (√2 per diagonal step).
    fn length(&self) -> f64 {
        1.0 + self
            .cells
            .windows(2)
            .map(|w| {
                if w[0].0 != w[1].0 && w[0].1 != w[1].1 {
                    std::f64::consts::SQRT_2
                } else {
                    1.0
                }
            })
            .sum::<f64>()
    }
}

/// The cells 8-connected to `start` through cells that `take` accepts (and marks as taken, so
/// it accepts each once), `start` first, in breadth-first order.
fn grow(
    start: (isize, isize),
    mut take: impl FnMut((isize, isize)) -> bool,
) -> Vec<(isize, isize)> {
    let mut cells = vec![start];
    let mut k = 0;
    while k < cells.len() {
        let (r, c) = cells[k];
        k += 1;
        for (dx, dy) in crackbot_imaging::thinning::NEIGHBOUR_OFFSETS {
            if take((r + dy, c + dx)) {
                cells.push((r + dy, c + dx));
            }
        }
    }
    cells
}

/// Angle between two directions, degrees.
fn angle_deg(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] * b[0] + a[1] * b[1])
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// A branch cut into runs at its corners: cells where the centre line turns by more than
/// [`CORNER_DEG`] between the [`DIRECTION_CELLS`] cells before and after (the sharpest cell of
/// each such stretch), leaving at least twice as many cells either side. The cut ends are free,
/// so the gap rule below sees them as ends that do not point at each other.
fn split_at_corners(branch: Branch) -> Vec<Branch> {
    let cells = &branch.cells;
    let k = DIRECTION_CELLS;
    // Both runs at least twice the direction's reach: the centre line of a wide crack hooks
    // at its ends (a 10 mm crack's by about 6 mm), and a hook is no crack of its own.
    let arm = 2 * k;
    if cells.len() < 2 * arm + 2 {
        return vec![branch];
    }
    let unit = |a: (isize, isize), b: (isize, isize)| {
        let d = [(b.1 - a.1) as f64, (b.0 - a.0) as f64];
        let l = d[0].hypot(d[1]);
        [d[0] / l, d[1] / l]
    };
    // The turn at each cell that may be cut, `arm..len - arm`.
    let turns: Vec<f64> = (arm..cells.len() - arm)
        .map(|i| angle_deg(unit(cells[i - k], cells[i]), unit(cells[i], cells[i + k])))
        .collect();
    // The sharpest cell of each stretch turning by more than the corner angle.
    let mut cuts = Vec::new();
    let mut stretch: Option<usize> = None;
    for (j, &t) in turns.iter().enumerate() {
        if t > CORNER_DEG {
            stretch = Some(stretch.filter(|&b| turns[b] >= t).unwrap_or(j));
        } else if let Some(b) = stretch.take() {
            cuts.push(arm + b);
        }
    }
    cuts.extend(stretch.map(|b| arm + b));
    if cuts.is_empty() {
        return vec![branch];
    }
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut from = 0;
    for (n, &cut) in cuts.iter().chain(std::iter::once(&cells.len())).enumerate() {
        let to = if n < cuts.len() { cut + 1 } else { cut };
        out.push(Branch {
            cells: cells[from..to].to_vec(),
            junction: [
                if from == 0 { branch.junction[0] } else { None },
                if to == cells.len() {
                    branch.junction[1]
                } else {
                    None
                },
            ],
        });
        from = to;
    }
    out
}

/// The cracks of one component (cells `(row, column)`), where the finger should touch each (see
/// the [module docs](self)); `max_gap` cells is the longest gap the dilation joined; `to_img`
/// image pixels per cell.
#[allow(
    clippy::too_many_lines,
    reason = "the map-to-pieces walk; its failure cases (joined cracks) are under study in issue 56, split it with that fix"
)]
fn pieces(cells: &[(usize, usize)], max_gap: usize, to_img: f32) -> Vec<CrackPiece> {
    let Some(r0) = cells.iter().map(|c| c.0).min() else {
        return Vec::new();
    };
    let c0 = cells.iter().map(|c| c.1).min().unwrap_or(0);
    let rows = cells.iter().map(|c| c.0).max().unwrap_or(0) - r0 + 3;
    let cols = cells.iter().map(|c| c.1).max().unwrap_or(0) - c0 + 3;
    // A one-cell margin, so the thinning never meets the edge.
    let mut grid = vec![false; rows * cols];
    for &(r, c) in cells {
        grid[(r - r0 + 1) * cols + (c - c0 + 1)] = true;
    }
    let crack = grid.clone();
    crackbot_imaging::thinning::thin(&mut grid, cols);
    use crackbot_imaging::thinning::{neighbours, pixel, NEIGHBOUR_OFFSETS};
    let on = |r: isize, c: isize| pixel(&grid, cols, c, r);
    // The neighbour offsets as (row, column).
    let around = NEIGHBOUR_OFFSETS.map(|(dx, dy)| (dy, dx));
    let degree = |r: isize, c: isize| neighbours(&grid, cols, c, r).iter().filter(|&&n| n).count();
    // Junction cells (three or more neighbours), grouped into junctions by 8-adjacency.
    let mut junction_of = vec![usize::MAX; rows * cols];
    let mut junction_cells: Vec<Vec<(isize, isize)>> = Vec::new();
    for r in 0..rows as isize {
        for c in 0..cols as isize {
            let i = r as usize * cols + c as usize;
            if !on(r, c) || degree(r, c) < 3 || junction_of[i] != usize::MAX {
                continue;
            }
            let id = junction_cells.len();
            junction_of[i] = id;
            let group = grow((r, c), |(nr, nc)| {
                if !on(nr, nc) || degree(nr, nc) < 3 {
                    return false;
                }
                let j = nr as usize * cols + nc as usize;
                let take = junction_of[j] == usize::MAX;
                if take {
                    junction_of[j] = id;
                }
                take
            });
            junction_cells.push(group);
        }
    }
    let is_junction =
        |r: isize, c: isize| junction_of[r as usize * cols + c as usize] != usize::MAX;
    // Branches: runs of the other centre-line cells (each has at most two such neighbours).
    let mut seen = vec![false; rows * cols];
    let mut branches: Vec<Branch> = Vec::new();
    for r in 0..rows as isize {
        for c in 0..cols as isize {
            let i = r as usize * cols + c as usize;
            if !on(r, c) || is_junction(r, c) || seen[i] {
                continue;
            }
            // The run's cells, then walk it from one end.
            seen[i] = true;
            let run = grow((r, c), |(nr, nc)| {
                if !on(nr, nc) || is_junction(nr, nc) {
                    return false;
                }
                let j = nr as usize * cols + nc as usize;
                let take = !seen[j];
                seen[j] = true;
                take
            });
            let inside = |p: (isize, isize)| {
                around
                    .iter()
                    .filter(|d| run.contains(&(p.0 + d.0, p.1 + d.1)))
                    .count()
            };
            let start = run
                .iter()
                .copied()
                .find(|&p| inside(p) <= 1)
                .unwrap_or(run[0]);
            let mut ordered = vec![start];
            let mut used = vec![false; run.len()];
            if let Some(k) = run.iter().position(|&p| p == start) {
                used[k] = true;
            }
            // Walk to an unused run neighbour, 4-neighbours first (so diagonal shortcuts of a
            // staircase are not skipped).
            loop {
                let (gr, gc) = ordered[ordered.len() - 1];
                let mut next = None;
                for d in [0, 2, 4, 6, 1, 3, 5, 7].map(|k| around[k]) {
                    if let Some(k) = run
                        .iter()
                        .position(|&p| p == (gr + d.0, gc + d.1))
                        .filter(|&k| !used[k])
                    {
                        next = Some(k);
                        break;
                    }
                }
                match next {
                    Some(k) => {
                        used[k] = true;
                        ordered.push(run[k]);
                    }
                    None => break,
                }
            }
            // The junction an end touches, other than `not`.
            let touching = |p: (isize, isize), not: Option<usize>| {
                around.iter().find_map(|d| {
                    let (nr, nc) = (p.0 + d.0, p.1 + d.1);
                    let j = (on(nr, nc) && is_junction(nr, nc))
                        .then(|| junction_of[nr as usize * cols + nc as usize]);
                    j.filter(|&j| Some(j) != not)
                })
            };
            let first = ordered[0];
            let last = ordered[ordered.len() - 1];
            let j0 = touching(first, None);
            // A one-cell branch between two junctions touches both.
            let j1 = match ordered.len() {
                1 => touching(last, j0).or(j0),
                _ => touching(last, None),
            };
            let junction = [j0, j1];
            branches.push(Branch {
                cells: ordered,
                junction,
            });
        }
    }
    // Two cracks that meet at a corner (a V) thin to one branch: split it where it turns.
    let mut branches: Vec<Branch> = branches.into_iter().flat_map(split_at_corners).collect();
    // Spurs: a free end, a junction at the other, short.
    branches.retain(|b| {
        let free = b.junction.iter().filter(|j| j.is_none()).count();
        !(free == 1 && b.length() < SPUR_CELLS as f64)
    });
    // Two lines crossing at a slant, or thick, thin to two junctions joined by a short bridge:
    // one crossing. The bridge goes and its junctions become one.
    let mut merged = Sets::new(junction_cells.len());
    branches.retain(|b| match b.junction {
        [Some(a), Some(c)] if a != c && b.length() <= BRIDGE_CELLS as f64 => {
            merged.union(a, c);
            false
        }
        _ => true,
    });
    for b in &mut branches {
        for j in b.junction.iter_mut().flatten() {
            *j = merged.find(*j);
        }
    }
    let mut sets = Sets::new(branches.len());
    // Through each junction, the pairs of branches that continue each other best.
    for j in 0..junction_cells.len() {
        let mut ends: Vec<(usize, usize, [f64; 2])> = Vec::new();
        for (bi, b) in branches.iter().enumerate() {
            for e in 0..2 {
                if b.junction[e] == Some(j)
                    && !(e == 1 && b.cells.len() == 1 && b.junction[0] == Some(j))
                {
                    // Pointing into the branch, away from the junction: the opposite of outward.
                    let o = b.outward(e);
                    ends.push((bi, e, [-o[0], -o[1]]));
                }
            }
        }
        loop {
            let mut best: Option<(f64, usize, usize)> = None;
            for a in 0..ends.len() {
                for b in a + 1..ends.len() {
                    if ends[a].0 == ends[b].0 {
                        continue;
                    }
                    let (da, db) = (ends[a].2, ends[b].2);
                    // Straight on: the two leave the junction in opposite directions.
                    let bend = angle_deg(da, [-db[0], -db[1]]);
                    if bend <= CONTINUATION_DEG && best.is_none_or(|x| bend < x.0) {
                        best = Some((bend, a, b));
                    }
                }
            }
            let Some((_, a, b)) = best else { break };
            sets.union(ends[a].0, ends[b].0);
            let (hi, lo) = (a.max(b), a.min(b));
            ends.remove(hi);
            ends.remove(lo);
        }
    }
    // Across gaps the dilation joined: free ends that point at each other.
    let mut free: Vec<(usize, usize)> = Vec::new();
    for (bi, b) in branches.iter().enumerate() {
        for e in 0..2 {
            if b.junction[e].is_none() && b.cells.len() > 1 {
                free.push((bi, e));
            }
        }
    }
    let mut gaps: Vec<(f64, usize, usize)> = Vec::new();
    for a in 0..free.len() {
        for b in a + 1..free.len() {
            let ((ba, ea), (bb, eb)) = (free[a], free[b]);
            if ba == bb {
                continue;
            }
            let (pa, pb) = (branches[ba].end(ea), branches[bb].end(eb));
            let v = [(pb.1 - pa.1) as f64, (pb.0 - pa.0) as f64];
            let d = v[0].hypot(v[1]);
            if d > max_gap as f64 || d == 0.0 {
                continue;
            }
            let u = [v[0] / d, v[1] / d];
            let (oa, ob) = (branches[ba].outward(ea), branches[bb].outward(eb));
            // Each end points at the other, and the two go on from each other as straight as
            // through a junction: each end within the limit of the line between them alone
            // would let two cracks meeting in a V at up to twice the limit be joined.
            if angle_deg(oa, u) <= CONTINUATION_DEG
                && angle_deg(ob, [-u[0], -u[1]]) <= CONTINUATION_DEG
                && angle_deg(oa, [-ob[0], -ob[1]]) <= CONTINUATION_DEG
            {
                gaps.push((d, a, b));
            }
        }
    }
    gaps.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut end_used = vec![false; free.len()];
    for (_, a, b) in gaps {
        if !end_used[a] && !end_used[b] {
            end_used[a] = true;
            end_used[b] = true;
            sets.union(free[a].0, free[b].0);
        }
    }
    // Each joined run: length, touch point and local direction.
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of = vec![usize::MAX; branches.len()];
    for bi in 0..branches.len() {
        let root = sets.find(bi);
        if group_of[root] == usize::MAX {
            group_of[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[root]].push(bi);
    }
    let all_junctions: Vec<(isize, isize)> = junction_cells.iter().flatten().copied().collect();
    let img = |p: (f64, f64)| {
        // Grid cell (row, column) → image pixels of the map cell's centre.
        [
            ((p.1 + c0 as f64 - 1.0 + 0.5) * f64::from(to_img)) as f32,
            ((p.0 + r0 as f64 - 1.0 + 0.5) * f64::from(to_img)) as f32,
        ]
    };
    let mut out: Vec<CrackPiece> = Vec::new();
    for g in groups {
        let length: f64 = g.iter().map(|&b| branches[b].length()).sum();
        if length < MIN_PIECE_CELLS as f64 {
            continue;
        }
        let pts: Vec<(isize, isize)> = g
            .iter()
            .flat_map(|&b| branches[b].cells.iter().copied())
            .collect();
        let n = pts.len() as f64;
        let (mr, mc) = pts.iter().fold((0.0, 0.0), |a, p| {
            (a.0 + p.0 as f64 / n, a.1 + p.1 as f64 / n)
        });
        let clear = |p: &(isize, isize)| {
            all_junctions
                .iter()
                .all(|q| ((p.0 - q.0) as f64).hypot((p.1 - q.1) as f64) >= JUNCTION_CLEARANCE_CELLS)
        };
        let near = |p: &&(isize, isize)| (p.0 as f64 - mr).powi(2) + (p.1 as f64 - mc).powi(2);
        let touch = pts
            .iter()
            .filter(|p| clear(p))
            .min_by(|a, b| near(a).total_cmp(&near(b)))
            .or_else(|| pts.iter().min_by(|a, b| near(a).total_cmp(&near(b))))
            .copied()
            .unwrap_or((mr as isize, mc as isize));
        // Local direction: principal axis of the run's cells within a few cells of the touch.
        let local: Vec<&(isize, isize)> = pts
            .iter()
            .filter(|p| {
                ((p.0 - touch.0) as f64).hypot((p.1 - touch.1) as f64)
                    <= 2.0 * DIRECTION_CELLS as f64
            })
            .collect();
        let m = local.len().max(1) as f64;
        let (lr, lc) = local.iter().fold((0.0, 0.0), |a, p| {
            (a.0 + p.0 as f64 / m, a.1 + p.1 as f64 / m)
        });
        let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
        for p in &local {
            let (dx, dy) = (p.1 as f64 - lc, p.0 as f64 - lr);
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
        }
        let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let (ux, uy) = (theta.cos(), theta.sin());
        let half = length / 2.0;
        let t = (touch.0 as f64, touch.1 as f64);
        // Width: crack cells across the direction at the touch, both ways, in half-cell steps.
        let in_crack = |r: f64, c: f64| {
            let (r, c) = (r.round(), c.round());
            r >= 0.0
                && c >= 0.0
                && (r as usize) < rows
                && (c as usize) < cols
                && crack[r as usize * cols + c as usize]
        };
        let mut across = 0.0;
        for sign in [-1.0, 1.0] {
            let mut k = 1.0;
            while k < (rows + cols) as f64
                && in_crack(t.0 + sign * k * 0.5 * ux, t.1 - sign * k * 0.5 * uy)
            {
                k += 1.0;
            }
            across += (k - 1.0) * 0.5;
        }
        out.push(CrackPiece {
            width_px: ((across + 1.0) * f64::from(to_img)) as f32,
            touch: img(t),
            axis: [
                img((t.0 - half * uy, t.1 - half * ux)),
                img((t.0 + half * uy, t.1 + half * ux)),
            ],
            length_px: (length * f64::from(to_img)) as f32,
        });
    }
    out.sort_by(|a, b| b.length_px.total_cmp(&a.length_px));
    out
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
