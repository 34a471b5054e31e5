//! Where to touch: one component's crack cells → the cracks it holds, each a [`CrackPiece`]
//! (the steps are in the [parent's docs](super), "Where to touch"). [`pieces`] runs them in
//! order, one function each: thin, find junctions, trace branches, prune (corners, spurs,
//! bridges), pair branches through junctions and across gaps, and turn each joined run into a
//! piece.

use crackbot_imaging::thinning::{neighbours, pixel, thin, NEIGHBOUR_OFFSETS};

use crate::shape::CrackPiece;

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
pub(crate) const DIRECTION_CELLS: usize = 4;
/// Touch points keep at least this many cells from a junction when the piece allows.
pub(crate) const JUNCTION_CLEARANCE_CELLS: f64 = 3.0;

/// A grid cell, (row, column).
type Cell = (isize, isize);

/// The neighbour offsets as (row, column).
const AROUND: [Cell; 8] = {
    let mut out = [(0, 0); 8];
    let mut k = 0;
    while k < 8 {
        out[k] = (NEIGHBOUR_OFFSETS[k].1, NEIGHBOUR_OFFSETS[k].0);
        k += 1;
    }
    out
};

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

/// One branch of the centre line: its cells in order, and at each end the junction it meets
/// (`None`: a free end).
struct Branch {
    cells: Vec<Cell>,
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

    fn end(&self, e: usize) -> Cell {
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
fn grow(start: Cell, mut take: impl FnMut(Cell) -> bool) -> Vec<Cell> {
    let mut cells = vec![start];
    let mut k = 0;
    while k < cells.len() {
        let (r, c) = cells[k];
        k += 1;
        for (dr, dc) in AROUND {
            if take((r + dr, c + dc)) {
                cells.push((r + dr, c + dc));
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

/// A component's crack cells on a grid of their own, with a one-cell margin so the thinning
/// never meets the edge.
struct Patch {
    rows: usize,
    cols: usize,
    /// Map cell of the grid's cell (1, 1).
    origin: (usize, usize),
    crack: Vec<bool>,
}

impl Patch {
    fn new(cells: &[(usize, usize)]) -> Option<Self> {
        let r0 = cells.iter().map(|c| c.0).min()?;
        let c0 = cells.iter().map(|c| c.1).min()?;
        let rows = cells.iter().map(|c| c.0).max()? - r0 + 3;
        let cols = cells.iter().map(|c| c.1).max()? - c0 + 3;
        let mut crack = vec![false; rows * cols];
        for &(r, c) in cells {
            crack[(r - r0 + 1) * cols + (c - c0 + 1)] = true;
        }
        Some(Patch {
            rows,
            cols,
            origin: (r0, c0),
            crack,
        })
    }

    /// Grid position (row, column) → image pixels (x, y) of the map cell's centre.
    fn to_image(&self, p: (f64, f64), to_img: f32) -> [f32; 2] {
        let (r0, c0) = (self.origin.0 as f64, self.origin.1 as f64);
        [
            ((p.1 + c0 - 1.0 + 0.5) * f64::from(to_img)) as f32,
            ((p.0 + r0 - 1.0 + 0.5) * f64::from(to_img)) as f32,
        ]
    }

    /// Whether the grid position nearest (r, c) is a crack cell.
    fn in_crack(&self, r: f64, c: f64) -> bool {
        let (r, c) = (r.round(), c.round());
        r >= 0.0
            && c >= 0.0
            && (r as usize) < self.rows
            && (c as usize) < self.cols
            && self.crack[r as usize * self.cols + c as usize]
    }
}

/// A thinned centre line on its patch's grid.
struct Skeleton {
    grid: Vec<bool>,
    rows: usize,
    cols: usize,
}

impl Skeleton {
    fn on(&self, (r, c): Cell) -> bool {
        pixel(&self.grid, self.cols, c, r)
    }
    fn degree(&self, (r, c): Cell) -> usize {
        neighbours(&self.grid, self.cols, c, r)
            .iter()
            .filter(|&&n| n)
            .count()
    }
    fn index(&self, (r, c): Cell) -> usize {
        r as usize * self.cols + c as usize
    }
    /// Every centre-line cell, in raster order.
    fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        (0..self.rows as isize)
            .flat_map(move |r| (0..self.cols as isize).map(move |c| (r, c)))
            .filter(|&p| self.on(p))
    }
}

/// The junctions of a centre line: cells with three or more neighbours, grouped by
/// 8-adjacency. Returns each grid cell's junction (`usize::MAX`: none) and each junction's cells.
fn junctions(sk: &Skeleton) -> (Vec<usize>, Vec<Vec<Cell>>) {
    let mut junction_of = vec![usize::MAX; sk.rows * sk.cols];
    let mut junction_cells: Vec<Vec<Cell>> = Vec::new();
    for p in sk.cells() {
        if sk.degree(p) < 3 || junction_of[sk.index(p)] != usize::MAX {
            continue;
        }
        let id = junction_cells.len();
        junction_of[sk.index(p)] = id;
        let group = grow(p, |q| {
            if !sk.on(q) || sk.degree(q) < 3 {
                return false;
            }
            let take = junction_of[sk.index(q)] == usize::MAX;
            if take {
                junction_of[sk.index(q)] = id;
            }
            take
        });
        junction_cells.push(group);
    }
    (junction_of, junction_cells)
}

/// The cells of a run (each with at most two run neighbours) in order along it, from an end
/// (a cell with one run neighbour; any cell of a closed loop). Steps go to 4-neighbours first,
/// so the diagonal shortcuts of a staircase are not skipped.
fn order_run(run: &[Cell]) -> Vec<Cell> {
    let inside = |p: Cell| {
        AROUND
            .iter()
            .filter(|d| run.contains(&(p.0 + d.0, p.1 + d.1)))
            .count()
    };
    let start = run.iter().position(|&p| inside(p) <= 1).unwrap_or_default();
    let mut used = vec![false; run.len()];
    used[start] = true;
    let mut ordered = vec![run[start]];
    loop {
        let (gr, gc) = ordered[ordered.len() - 1];
        let next = [0, 2, 4, 6, 1, 3, 5, 7].iter().find_map(|&k| {
            let d = AROUND[k];
            run.iter()
                .position(|&p| p == (gr + d.0, gc + d.1))
                .filter(|&k| !used[k])
        });
        let Some(k) = next else { break };
        used[k] = true;
        ordered.push(run[k]);
    }
    ordered
}

/// The branches of a centre line: runs of its non-junction cells, ordered, each with the
/// junctions its ends touch.
fn trace_branches(sk: &Skeleton, junction_of: &[usize]) -> Vec<Branch> {
    let junction_at = |p: Cell| -> Option<usize> {
        (sk.on(p) && junction_of[sk.index(p)] != usize::MAX).then(|| junction_of[sk.index(p)])
    };
    // The junction an end touches, other than `not`.
    let touching = |p: Cell, not: Option<usize>| {
        AROUND
            .iter()
            .find_map(|d| junction_at((p.0 + d.0, p.1 + d.1)).filter(|&j| Some(j) != not))
    };
    let mut seen = vec![false; sk.rows * sk.cols];
    let mut branches = Vec::new();
    for p in sk.cells() {
        if junction_at(p).is_some() || seen[sk.index(p)] {
            continue;
        }
        seen[sk.index(p)] = true;
        let run = grow(p, |q| {
            if !sk.on(q) || junction_at(q).is_some() {
                return false;
            }
            let take = !seen[sk.index(q)];
            seen[sk.index(q)] = true;
            take
        });
        let cells = order_run(&run);
        let j0 = touching(cells[0], None);
        // A one-cell branch between two junctions touches both.
        let j1 = match cells.len() {
            1 => touching(cells[0], j0).or(j0),
            n => touching(cells[n - 1], None),
        };
        branches.push(Branch {
            cells,
            junction: [j0, j1],
        });
    }
    branches
}

/// A branch cut into runs at its corners: cells where the centre line turns by more than
/// [`CORNER_DEG`] between the [`DIRECTION_CELLS`] cells before and after (the sharpest cell of
/// each such stretch), leaving at least twice as many cells either side. The cut ends are free,
/// so the gap rule sees them as ends that do not point at each other.
fn split_at_corners(branch: Branch) -> Vec<Branch> {
    let cells = &branch.cells;
    let k = DIRECTION_CELLS;
    // Both runs at least twice the direction's reach: the centre line of a wide crack hooks
    // at its ends (a 10 mm crack's by about 6 mm), and a hook is no crack of its own.
    let arm = 2 * k;
    if cells.len() < 2 * arm + 2 {
        return vec![branch];
    }
    let unit = |a: Cell, b: Cell| {
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

/// Branches cut at their corners (two cracks meeting in a V thin to one branch), without spurs
/// (a free end, a junction at the other, short), and without bridges: two lines crossing at a
/// slant, or thick, thin to two junctions joined by a short branch, one crossing, so the
/// bridge goes and its junctions become one (each branch's junctions are renumbered to it).
fn prune(branches: Vec<Branch>, n_junctions: usize) -> Vec<Branch> {
    let mut branches: Vec<Branch> = branches.into_iter().flat_map(split_at_corners).collect();
    branches.retain(|b| {
        let free = b.junction.iter().filter(|j| j.is_none()).count();
        !(free == 1 && b.length() < SPUR_CELLS as f64)
    });
    let mut merged = Sets::new(n_junctions);
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
    branches
}

/// Through each junction, joins the pairs of branches that continue each other best (the
/// straightest pair first, each end once, within [`CONTINUATION_DEG`] of straight).
fn pair_through_junctions(branches: &[Branch], n_junctions: usize, sets: &mut Sets) {
    for j in 0..n_junctions {
        // Each end at the junction, pointing into its branch, away from the junction.
        let mut ends: Vec<(usize, [f64; 2])> = Vec::new();
        for (bi, b) in branches.iter().enumerate() {
            for e in 0..2 {
                if b.junction[e] == Some(j)
                    && !(e == 1 && b.cells.len() == 1 && b.junction[0] == Some(j))
                {
                    let o = b.outward(e);
                    ends.push((bi, [-o[0], -o[1]]));
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
                    let (da, db) = (ends[a].1, ends[b].1);
                    // Straight on: the two leave the junction in opposite directions.
                    let bend = angle_deg(da, [-db[0], -db[1]]);
                    if bend <= CONTINUATION_DEG && best.is_none_or(|x| bend < x.0) {
                        best = Some((bend, a, b));
                    }
                }
            }
            let Some((_, a, b)) = best else { break };
            sets.union(ends[a].0, ends[b].0);
            ends.remove(a.max(b));
            ends.remove(a.min(b));
        }
    }
}

/// Across gaps the dilation joined (at most `max_gap` cells): joins free ends that point at
/// each other, the shortest gap first, each end once.
fn pair_across_gaps(branches: &[Branch], max_gap: usize, sets: &mut Sets) {
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
}

/// The joined runs: the branches of each set, sets in order of their first branch.
fn groups(n_branches: usize, sets: &mut Sets) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of = vec![usize::MAX; n_branches];
    for bi in 0..n_branches {
        let root = sets.find(bi);
        if group_of[root] == usize::MAX {
            group_of[root] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[root]].push(bi);
    }
    groups
}

/// Where to touch a run of centre-line cells `pts`: the cell nearest its centroid that keeps
/// [`JUNCTION_CLEARANCE_CELLS`] from every junction cell, else the cell nearest its centroid.
fn touch_point(pts: &[Cell], junction_cells: &[Cell]) -> Option<Cell> {
    let n = pts.len() as f64;
    let (mr, mc) = pts.iter().fold((0.0, 0.0), |a, p| {
        (a.0 + p.0 as f64 / n, a.1 + p.1 as f64 / n)
    });
    let clear = |p: &&Cell| {
        junction_cells
            .iter()
            .all(|q| ((p.0 - q.0) as f64).hypot((p.1 - q.1) as f64) >= JUNCTION_CLEARANCE_CELLS)
    };
    let near = |p: &&Cell| (p.0 as f64 - mr).powi(2) + (p.1 as f64 - mc).powi(2);
    let nearest = |it: &mut dyn Iterator<Item = &Cell>| {
        it.min_by(|a, b| near(a).total_cmp(&near(b))).copied()
    };
    nearest(&mut pts.iter().filter(clear)).or_else(|| nearest(&mut pts.iter()))
}

/// The run's direction at `touch` (unit (x, y)): the principal axis of its cells within twice
/// [`DIRECTION_CELLS`] of it.
fn local_direction(pts: &[Cell], touch: Cell) -> (f64, f64) {
    let reach = 2.0 * DIRECTION_CELLS as f64;
    let local: Vec<&Cell> = pts
        .iter()
        .filter(|p| ((p.0 - touch.0) as f64).hypot((p.1 - touch.1) as f64) <= reach)
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
    (theta.cos(), theta.sin())
}

/// Crack cells across direction `(ux, uy)` at `t`, both ways, in half-cell steps, plus the
/// cell itself.
fn width_across(patch: &Patch, t: (f64, f64), (ux, uy): (f64, f64)) -> f64 {
    let limit = (patch.rows + patch.cols) as f64;
    let mut across = 0.0;
    for sign in [-1.0, 1.0] {
        let mut k = 1.0;
        while k < limit && patch.in_crack(t.0 + sign * k * 0.5 * ux, t.1 - sign * k * 0.5 * uy) {
            k += 1.0;
        }
        across += (k - 1.0) * 0.5;
    }
    across + 1.0
}

/// One joined run's piece, `None` when it is shorter than [`MIN_PIECE_CELLS`].
fn piece(
    patch: &Patch,
    branches: &[Branch],
    group: &[usize],
    junction_cells: &[Cell],
    to_img: f32,
) -> Option<CrackPiece> {
    let length: f64 = group.iter().map(|&b| branches[b].length()).sum();
    if length < MIN_PIECE_CELLS as f64 {
        return None;
    }
    let pts: Vec<Cell> = group
        .iter()
        .flat_map(|&b| branches[b].cells.iter().copied())
        .collect();
    let touch = touch_point(&pts, junction_cells)?;
    let (ux, uy) = local_direction(&pts, touch);
    let half = length / 2.0;
    let t = (touch.0 as f64, touch.1 as f64);
    Some(CrackPiece {
        width_px: (width_across(patch, t, (ux, uy)) * f64::from(to_img)) as f32,
        touch: patch.to_image(t, to_img),
        axis: [
            patch.to_image((t.0 - half * uy, t.1 - half * ux), to_img),
            patch.to_image((t.0 + half * uy, t.1 + half * ux), to_img),
        ],
        length_px: (length * f64::from(to_img)) as f32,
    })
}

/// The cracks of one component (map cells `(row, column)`), where the finger should touch
/// each, longest first; `max_gap` cells is the longest gap the dilation joined; `to_img` image
/// pixels per cell.
pub(super) fn pieces(cells: &[(usize, usize)], max_gap: usize, to_img: f32) -> Vec<CrackPiece> {
    let Some(patch) = Patch::new(cells) else {
        return Vec::new();
    };
    let mut grid = patch.crack.clone();
    thin(&mut grid, patch.cols);
    let sk = Skeleton {
        grid,
        rows: patch.rows,
        cols: patch.cols,
    };
    let (junction_of, junction_cells) = junctions(&sk);
    let branches = prune(trace_branches(&sk, &junction_of), junction_cells.len());
    let mut sets = Sets::new(branches.len());
    pair_through_junctions(&branches, junction_cells.len(), &mut sets);
    pair_across_gaps(&branches, max_gap, &mut sets);
    let all_junctions: Vec<Cell> = junction_cells.concat();
    let mut out: Vec<CrackPiece> = groups(branches.len(), &mut sets)
        .iter()
        .filter_map(|g| piece(&patch, &branches, g, &all_junctions, to_img))
        .collect();
    out.sort_by(|a, b| b.length_px.total_cmp(&a.length_px));
    out
}
