//! The workspace, the speed limits and a little plane geometry (points are `[x, y]` mm).

use serde::{Deserialize, Serialize};

use crate::error::{finite, positive, PlanError};

/// A point on the surface, mm.
pub type Point = [f64; 2];

/// Euclidean distance, mm.
pub fn dist(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

pub(crate) fn add(a: Point, b: Point) -> Point {
    [a[0] + b[0], a[1] + b[1]]
}

pub(crate) fn scale(a: Point, s: f64) -> Point {
    [a[0] * s, a[1] * s]
}

pub(crate) fn dot(a: Point, b: Point) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The rectangle the finger's tip centre may reach on the surface, mm (inclusive bounds).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Workspace {
    /// Lowest x, mm.
    pub x_min_mm: f64,
    /// Highest x, mm.
    pub x_max_mm: f64,
    /// Lowest y, mm.
    pub y_min_mm: f64,
    /// Highest y, mm.
    pub y_max_mm: f64,
}

impl Workspace {
    /// A checked workspace: every bound finite, `min < max` on both axes.
    pub fn new(
        x_min_mm: f64,
        x_max_mm: f64,
        y_min_mm: f64,
        y_max_mm: f64,
    ) -> Result<Self, PlanError> {
        let w = Workspace {
            x_min_mm,
            x_max_mm,
            y_min_mm,
            y_max_mm,
        };
        w.validate()?;
        Ok(w)
    }

    /// `[0, width] × [0, height]` mm (the paper's plate: 200 × 100).
    pub fn from_size(width_mm: f64, height_mm: f64) -> Result<Self, PlanError> {
        Self::new(0.0, width_mm, 0.0, height_mm)
    }

    /// Checks the bounds (the planner calls it on every workspace it is given).
    pub fn validate(&self) -> Result<(), PlanError> {
        finite("workspace.x_min_mm", self.x_min_mm)?;
        finite("workspace.x_max_mm", self.x_max_mm)?;
        finite("workspace.y_min_mm", self.y_min_mm)?;
        finite("workspace.y_max_mm", self.y_max_mm)?;
        for (axis, lo, hi) in [
            ("x", self.x_min_mm, self.x_max_mm),
            ("y", self.y_min_mm, self.y_max_mm),
        ] {
            if !(hi - lo > 0.0 && (hi - lo).is_finite()) {
                return Err(PlanError::InvalidParam {
                    field: format!("workspace.{axis}_max_mm - workspace.{axis}_min_mm"),
                    value: hi - lo,
                    expected: "a finite extent > 0 (max above min)",
                });
            }
        }
        Ok(())
    }

    /// Extent along x, mm.
    pub fn width_mm(&self) -> f64 {
        self.x_max_mm - self.x_min_mm
    }

    /// Extent along y, mm (the `h` of eq. 2 once mapped to millimetres).
    pub fn height_mm(&self) -> f64 {
        self.y_max_mm - self.y_min_mm
    }

    /// Whether `p` lies inside or on the boundary.
    pub fn contains(&self, p: Point) -> bool {
        p[0] >= self.x_min_mm
            && p[0] <= self.x_max_mm
            && p[1] >= self.y_min_mm
            && p[1] <= self.y_max_mm
    }

    /// `p` moved to the nearest point inside (a no-op for points inside; used to absorb the
    /// last-bit rounding of endpoints computed on the boundary).
    pub fn clamp(&self, p: Point) -> Point {
        [
            p[0].clamp(self.x_min_mm, self.x_max_mm),
            p[1].clamp(self.y_min_mm, self.y_max_mm),
        ]
    }

    /// The parameters `s` for which `p + s·d` is inside, as `[lo, hi]`, or `None` when the line
    /// misses the workspace. `d` need not be a unit vector.
    pub fn line_interval(&self, p: Point, d: Point) -> Option<[f64; 2]> {
        let mut lo = f64::NEG_INFINITY;
        let mut hi = f64::INFINITY;
        for (k, (min, max)) in [
            (self.x_min_mm, self.x_max_mm),
            (self.y_min_mm, self.y_max_mm),
        ]
        .into_iter()
        .enumerate()
        {
            if d[k].abs() < 1e-12 {
                if p[k] < min || p[k] > max {
                    return None;
                }
            } else {
                let a = (min - p[k]) / d[k];
                let b = (max - p[k]) / d[k];
                lo = lo.max(a.min(b));
                hi = hi.min(a.max(b));
            }
        }
        (lo <= hi).then_some([lo, hi])
    }
}

impl std::fmt::Display for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "[{}, {}] × [{}, {}] mm",
            self.x_min_mm, self.x_max_mm, self.y_min_mm, self.y_max_mm
        )
    }
}

/// The robot's speed limits. Nothing faster is ever planned: settings above them are refused.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Fastest slide with the finger on the surface, mm/s.
    pub max_slide_speed_mm_s: f64,
    /// Fastest move with the finger lifted, mm/s.
    pub max_travel_speed_mm_s: f64,
}

impl Default for Limits {
    /// Placeholders until the manipulator's own figures are known: slides at most 10 mm/s
    /// (about twice the speed the tactile classifiers were trained at, 3.89–4.6 mm/s; faster
    /// slides change the signals), travel at most 100 mm/s.
    fn default() -> Self {
        Limits {
            max_slide_speed_mm_s: 10.0,
            max_travel_speed_mm_s: 100.0,
        }
    }
}

impl Limits {
    /// Checks that both limits are finite and positive.
    pub fn validate(&self) -> Result<(), PlanError> {
        positive("limits.max_slide_speed_mm_s", self.max_slide_speed_mm_s)?;
        positive("limits.max_travel_speed_mm_s", self.max_travel_speed_mm_s)
    }
}

/// Whether two oriented rectangles (centre, unit axis, half length along it, half width across
/// it) intersect or touch: the separating-axis test on their four edge directions.
pub(crate) fn rectangles_overlap(a: &OrientedRect, b: &OrientedRect) -> bool {
    let axes = [a.axis, a.normal(), b.axis, b.normal()];
    let delta = [b.centre[0] - a.centre[0], b.centre[1] - a.centre[1]];
    axes.iter().all(|ax| {
        let ra = a.half_len * dot(a.axis, *ax).abs() + a.half_wid * dot(a.normal(), *ax).abs();
        let rb = b.half_len * dot(b.axis, *ax).abs() + b.half_wid * dot(b.normal(), *ax).abs();
        dot(delta, *ax).abs() <= ra + rb + 1e-9
    })
}

/// A rectangle on the surface, along a unit axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct OrientedRect {
    pub centre: Point,
    pub axis: Point,
    pub half_len: f64,
    pub half_wid: f64,
}

impl OrientedRect {
    pub fn normal(&self) -> Point {
        [-self.axis[1], self.axis[0]]
    }

    pub fn corners(&self) -> [Point; 4] {
        let a = scale(self.axis, self.half_len);
        let n = scale(self.normal(), self.half_wid);
        [
            add(self.centre, add(a, n)),
            add(self.centre, add(a, scale(n, -1.0))),
            add(self.centre, add(scale(a, -1.0), n)),
            add(self.centre, add(scale(a, -1.0), scale(n, -1.0))),
        ]
    }
}

/// Groups of the items `0..n` that `linked` joins (transitively): each group in index order, the
/// groups in the order of their first member.
pub fn connected_groups(n: usize, mut linked: impl FnMut(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..n {
        for j in i + 1..n {
            if linked(i, j) {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut index_of_root = vec![usize::MAX; n];
    for i in 0..n {
        let r = find(&mut parent, i);
        if index_of_root[r] == usize::MAX {
            index_of_root[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[index_of_root[r]].push(i);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_interval_of_a_box() {
        let w = Workspace::from_size(200.0, 100.0).unwrap();
        assert_eq!(
            w.line_interval([100.0, 50.0], [0.0, 1.0]),
            Some([-50.0, 50.0])
        );
        assert_eq!(w.line_interval([100.0, 150.0], [1.0, 0.0]), None);
        let [lo, hi] = w.line_interval([0.0, 0.0], [1.0, 1.0]).unwrap();
        assert_eq!((lo, hi), (0.0, 100.0));
    }

    #[test]
    fn bad_workspaces_name_the_field() {
        let e = Workspace::new(0.0, 0.0, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("workspace.x_max_mm"), "{e}");
        let e = Workspace::new(f64::NAN, 1.0, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("workspace.x_min_mm"), "{e}");
        let e = Workspace::new(-f64::MAX, f64::MAX, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("finite extent"), "{e}");
    }

    #[test]
    fn rectangles() {
        let r = |c: Point, deg: f64, l: f64, w: f64| OrientedRect {
            centre: c,
            axis: [deg.to_radians().cos(), deg.to_radians().sin()],
            half_len: l / 2.0,
            half_wid: w / 2.0,
        };
        assert!(rectangles_overlap(
            &r([0.0, 0.0], 0.0, 10.0, 2.0),
            &r([5.5, 0.0], 90.0, 10.0, 2.0)
        ));
        assert!(!rectangles_overlap(
            &r([0.0, 0.0], 0.0, 10.0, 2.0),
            &r([10.5, 0.0], 90.0, 10.0, 0.0)
        ));
        // Two points at the same place touch.
        assert!(rectangles_overlap(
            &r([1.0, 1.0], 0.0, 0.0, 0.0),
            &r([1.0, 1.0], 30.0, 0.0, 0.0)
        ));
        // Diagonal rectangles whose bounding boxes overlap but which do not.
        assert!(!rectangles_overlap(
            &r([0.0, 0.0], 45.0, 20.0, 1.0),
            &r([6.0, -6.0], 45.0, 20.0, 1.0)
        ));
    }
}
