//! The detector's crack map seen from the plate ([`CrackTrace`]): which points of the plate lie
//! on its crack cells, and how far a straight line between two points runs off it.

use crackbot_imaging::Homography;
use crackbot_vision::crack_map::{CrackMap, MAP_THRESHOLD};

/// A point of the plate is on the crack map when a crack cell lies within this distance, mm.
pub const TRACE_REACH_MM: f64 = 1.0;
/// Step along the line between two crossings, mm.
const TRACE_STEP_MM: f64 = 0.25;
/// Most samples along one line (25 m at [`TRACE_STEP_MM`]): a line longer than any plate is
/// sampled more coarsely rather than for ever.
const MAX_TRACE_STEPS: f64 = 100_000.0;

/// The detector's crack map seen from the plate: which points of the plate lie on its crack
/// cells (probability at least [`MAP_THRESHOLD`]).
#[derive(Debug, Clone)]
pub struct CrackTrace {
    crack: Vec<bool>,
    width: usize,
    height: usize,
    homography: Homography,
}

impl CrackTrace {
    /// The map of one frame, with the frame's pixel ↔ plate homography.
    pub fn new(map: &CrackMap, homography: Homography) -> Self {
        let lb = map.letterbox();
        CrackTrace {
            crack: map.to_image().iter().map(|&p| p >= MAP_THRESHOLD).collect(),
            width: lb.image_width as usize,
            height: lb.image_height as usize,
            homography,
        }
    }

    /// The pixels (indices into the mask) whose centres lie within `reach_mm` of the plate
    /// point `p` (mm), crack or not; none where `p` falls outside the frame.
    fn pixels_near(&self, p: [f64; 2], reach_mm: f64) -> impl Iterator<Item = usize> + '_ {
        let px = |q: [f64; 2]| self.homography.surface_to_pixel(q).ok();
        let disc = match (
            px(p),
            px([p[0] + reach_mm, p[1]]),
            px([p[0], p[1] + reach_mm]),
        ) {
            (Some(c), Some(ex), Some(ey)) => Some((
                c,
                (ex[0] - c[0])
                    .hypot(ex[1] - c[1])
                    .max((ey[0] - c[0]).hypot(ey[1] - c[1])),
            )),
            _ => None,
        };
        let span = |v: f64, r: f64, n: usize| {
            let lo = ((v - r - 0.5).floor().max(0.0) as usize).min(n);
            let hi = ((v + r + 0.5).ceil().max(0.0) as usize).min(n);
            lo..hi
        };
        let (w, h) = (self.width, self.height);
        disc.into_iter().flat_map(move |(c, r)| {
            span(c[1], r, h).flat_map(move |y| {
                span(c[0], r, w).filter_map(move |x| {
                    let (dx, dy) = (x as f64 + 0.5 - c[0], y as f64 + 0.5 - c[1]);
                    (dx * dx + dy * dy <= r * r).then_some(y * w + x)
                })
            })
        })
    }

    /// Whether a crack cell lies within `reach_mm` of the plate point `p` (mm); `false` where
    /// `p` falls outside the frame.
    pub fn near_crack(&self, p: [f64; 2], reach_mm: f64) -> bool {
        self.pixels_near(p, reach_mm).any(|i| self.crack[i])
    }

    /// The longest stretch of the straight line from `a` to `b` (plate mm) with no crack cell
    /// within `reach_mm`, mm (sampled every 0.25 mm; the whole line where it leaves the frame).
    /// Not a number where an end is not finite, so nothing compares as joined.
    pub fn longest_gap_mm(&self, a: [f64; 2], b: [f64; 2], reach_mm: f64) -> f64 {
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        if !length.is_finite() {
            return f64::NAN;
        }
        let steps = (length / TRACE_STEP_MM).ceil().clamp(1.0, MAX_TRACE_STEPS) as usize;
        let (mut gap, mut longest) = (0usize, 0usize);
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let p = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            if self.near_crack(p, reach_mm) {
                gap = 0;
            } else {
                gap += 1;
                longest = longest.max(gap);
            }
        }
        longest as f64 * length / steps as f64
    }

    /// The length of the shortest path from `a` to `b` (plate mm) that stays on the crack map
    /// (8-connected crack pixels, starting and ending within `reach_mm` of the points), mm on the
    /// plate; `None` where no such path exists or an end lies off the map.
    pub fn path_on_map_mm(&self, a: [f64; 2], b: [f64; 2], reach_mm: f64) -> Option<f64> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let on_map = |p| {
            self.pixels_near(p, reach_mm)
                .filter(|&i| self.crack[i])
                .collect::<Vec<_>>()
        };
        let (starts, goals) = (on_map(a), on_map(b));
        if starts.is_empty() || goals.is_empty() {
            return None;
        }
        let mut goal = vec![false; self.crack.len()];
        for &g in &goals {
            goal[g] = true;
        }
        // Dijkstra over pixels, lengths in plate mm between pixel centres (each pixel mapped to
        // the plate once, when first reached).
        let mut centres: Vec<Option<Option<[f64; 2]>>> = vec![None; self.crack.len()];
        let mut centre = |i: usize| {
            *centres[i].get_or_insert_with(|| {
                let (x, y) = (i % self.width, i / self.width);
                self.homography
                    .pixel_to_surface([x as f64 + 0.5, y as f64 + 0.5])
                    .ok()
            })
        };
        let mut dist = vec![f64::INFINITY; self.crack.len()];
        let mut heap = BinaryHeap::new();
        for &s in &starts {
            dist[s] = 0.0;
            heap.push((Reverse(0u64), s));
        }
        while let Some((Reverse(d_bits), i)) = heap.pop() {
            let d = f64::from_bits(d_bits);
            if d > dist[i] {
                continue;
            }
            if goal[i] {
                return Some(d);
            }
            let (x, y) = ((i % self.width) as isize, (i / self.width) as isize);
            let Some(pi) = centre(i) else { continue };
            for (dx, dy) in [
                (-1, -1),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= self.width as isize || ny >= self.height as isize {
                    continue;
                }
                let j = ny as usize * self.width + nx as usize;
                if !self.crack[j] {
                    continue;
                }
                let Some(pj) = centre(j) else { continue };
                let nd = d + (pj[0] - pi[0]).hypot(pj[1] - pi[1]);
                if nd < dist[j] {
                    dist[j] = nd;
                    // Non-negative finite f64s order as their bits do.
                    heap.push((Reverse(nd.to_bits()), j));
                }
            }
        }
        None
    }
}

/// A 100 × 100 mm plate seen as a 200 × 200 px frame (0.5 mm a pixel, one map cell a mm),
/// with crack cells at `(row, column)`: row `r` is the plate's `y = r` mm.
#[cfg(test)]
pub(crate) fn trace_of(cells: &[(usize, usize)]) -> CrackTrace {
    use crackbot_vision::preprocess::Letterbox;
    let mut prob = vec![0.0f32; 100 * 100];
    for &(r, c) in cells {
        prob[r * 100 + c] = 0.9;
    }
    let map = CrackMap::new(prob, Letterbox::new(200, 200, 200).unwrap()).unwrap();
    let h = Homography::from_matrix([[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 1.0]]);
    CrackTrace::new(&map, h.unwrap())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_over_the_crack_map_follows_its_bends_and_stops_at_its_gaps() {
        // An L: along y = 20 from x = 10 to 50, then up x = 50 to y = 60; apart, y = 80 with a
        // 6 mm gap at x = 30.
        let mut cells: Vec<(usize, usize)> = (10..=50).map(|c| (20, c)).collect();
        cells.extend((20..=60).map(|r| (r, 50)));
        cells.extend((10..30).chain(36..60).map(|c| (80, c)));
        let trace = trace_of(&cells);
        // Around the corner: 40 + 40 mm give or take a cell, where the straight line is 56.6.
        let around = trace
            .path_on_map_mm([10.5, 20.5], [50.5, 60.5], 1.0)
            .expect("the L is connected");
        assert!((77.0..=81.0).contains(&around), "{around}");
        assert_eq!(trace.path_on_map_mm([10.5, 20.5], [10.5, 80.5], 1.0), None);
        assert_eq!(trace.path_on_map_mm([15.5, 80.5], [45.5, 80.5], 1.0), None);
        // Off the map, outside the frame or not a number: no path.
        assert_eq!(trace.path_on_map_mm([10.5, 40.5], [50.5, 60.5], 1.0), None);
        assert_eq!(
            trace.path_on_map_mm([-500.0, 20.5], [50.5, 60.5], 1.0),
            None
        );
        assert_eq!(
            trace.path_on_map_mm([f64::NAN, 20.5], [50.5, 60.5], 1.0),
            None
        );
        let here = trace.path_on_map_mm([30.5, 20.5], [30.5, 20.5], 1.0);
        assert_eq!(here, Some(0.0));
    }
}
