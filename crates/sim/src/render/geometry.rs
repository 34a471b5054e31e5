//! Geometry of the renderer: polylines queried by arc length and signed distance, the pixel
//! rectangle a plate region covers, the plate point seen through a pixel, and the image scale.

use crate::camera::{apply_homography, Camera};
use crate::surface::Point;

/// A pixel rectangle `[c0, c1) × [r0, r1)` as `(c0, c1, r0, r1)`.
pub(super) type Region = (usize, usize, usize, usize);

/// The plate point seen through the centre of every pixel, row by row, through the camera's
/// lens (`None` at or above the horizon).
pub(super) fn plate_points(cam: &Camera) -> Vec<Option<Point>> {
    let (w, h) = (cam.width() as usize, cam.height() as usize);
    (0..w * h)
        .map(|k| cam.plate_point([(k % w) as f64 + 0.5, (k / w) as f64 + 0.5]))
        .collect()
}

/// A polyline prepared for (arc length, signed distance) queries.
pub(super) struct Path2 {
    pub(super) a: Vec<Point>,
    pub(super) dir: Vec<Point>,
    len: Vec<f64>,
    cum: Vec<f64>,
    pub(super) total: f64,
}

impl Path2 {
    pub(super) fn new(path: &[Point]) -> Path2 {
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
    pub(super) fn locate(&self, q: Point) -> Option<(f64, f64, usize)> {
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

    pub(super) fn point_at(&self, s: f64) -> Point {
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
pub(super) fn pixel_region(cam: &Camera, lo: Point, hi: Point, z: &[f64]) -> Option<Region> {
    let (w, h) = (f64::from(cam.width()), f64::from(cam.height()));
    let mut umin = f64::INFINITY;
    let mut umax = f64::NEG_INFINITY;
    let mut vmin = f64::INFINITY;
    let mut vmax = f64::NEG_INFINITY;
    for &zz in z {
        // Corners and points along the edges: through a distorting lens the edges bow.
        let n = 4;
        let along = |k: usize| -> Point {
            let t = k as f64 / n as f64;
            [lo[0] + t * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1])]
        };
        let border = (0..=n).flat_map(|k| {
            let a = along(k);
            [[a[0], lo[1]], [a[0], hi[1]], [lo[0], a[1]], [hi[0], a[1]]]
        });
        for p in border {
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
pub(super) fn mm_per_px(cam: &Camera, p: Point) -> f64 {
    let h = cam.plate_to_image();
    let d = |a: Point, b: Point| match (apply_homography(&h, a), apply_homography(&h, b)) {
        (Some(x), Some(y)) => ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2)).sqrt(),
        _ => 1.0,
    };
    let dx = d([p[0] - 0.5, p[1]], [p[0] + 0.5, p[1]]);
    let dy = d([p[0], p[1] - 0.5], [p[0], p[1] + 0.5]);
    1.0 / (dx * dy).sqrt().max(1e-9)
}
