//! The trial scenes' geometry the scoring needs: distances between segments and polylines, how
//! far apart a scene's features lie ([`clearance_mm`]), and what a stroke meets.

use crackbot_sim::surface::distance_to_polyline;
use crackbot_sim::{Feature, Scene};

/// Distance between segments `a`–`b` and `c`–`d` (0 when they cross), mm.
pub(crate) fn segment_distance(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])
    };
    let (d1, d2) = (cross(a, b, c), cross(a, b, d));
    let (d3, d4) = (cross(c, d, a), cross(c, d, b));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return 0.0;
    }
    [
        distance_to_polyline(&[c, d], a),
        distance_to_polyline(&[c, d], b),
        distance_to_polyline(&[a, b], c),
        distance_to_polyline(&[a, b], d),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// Least distance between two polylines (0 where they cross), mm.
pub(crate) fn polyline_distance(p: &[[f64; 2]], q: &[[f64; 2]]) -> f64 {
    p.windows(2)
        .flat_map(|s| {
            q.windows(2)
                .map(move |t| segment_distance(s[0], s[1], t[0], t[1]))
        })
        .fold(f64::INFINITY, f64::min)
}

/// Whether `p` lies in the axis-aligned rectangle `min`–`max` (edges included).
pub(crate) fn in_rectangle(min: [f64; 2], max: [f64; 2], p: [f64; 2]) -> bool {
    (min[0]..=max[0]).contains(&p[0]) && (min[1]..=max[1]).contains(&p[1])
}

/// Lines kept at least this far, edge to edge, from every other feature of their scene stand
/// apart, mm: the paper's plates, a crack or a print alone under the finger. A stroke reaches
/// [`crackbot_mission::inspect::TOUCH_MARGIN_MM`] plus the finger's reach (2.4 mm) beyond the edge of the line
/// it crosses, so a feature beyond that cannot share its stroke; the crack map's detections join
/// lines within about twice its dilation (0.02 of the frame, 4 mm on the trial plates). 5 mm is
/// the first, rounded up; the trials split their score at it ([`ClearanceSplit`]).
pub const APART_MM: f64 = 5.0;

/// Edge-to-edge gap between a crack or printed decoy and another feature, mm (0 where they touch
/// or cross); `None` where neither is a line (a screw beside a bump matters to no stroke).
pub fn feature_gap_mm(a: &Feature, b: &Feature) -> Option<f64> {
    fn line(f: &Feature) -> Option<(&[[f64; 2]], f64)> {
        match f {
            Feature::Crack { path, width_mm, .. } | Feature::Decoy { path, width_mm, .. } => {
                Some((path.as_slice(), width_mm / 2.0))
            }
            _ => None,
        }
    }
    let (path, half, other) = match (line(a), line(b)) {
        (Some((pa, ha)), Some((pb, hb))) => {
            return Some((polyline_distance(pa, pb) - ha - hb).max(0.0));
        }
        (Some((p, h)), None) => (p, h, b),
        (None, Some((p, h))) => (p, h, a),
        (None, None) => return None,
    };
    let gap = match other {
        Feature::Bump {
            centre, radius_mm, ..
        } => distance_to_polyline(path, *centre) - radius_mm,
        Feature::Screw {
            centre,
            head_diameter_mm,
            ..
        } => distance_to_polyline(path, *centre) - head_diameter_mm / 2.0,
        Feature::Wavy { min, max, .. } => {
            if path.iter().any(|&p| in_rectangle(*min, *max, p)) {
                0.0
            } else {
                let outline = [*min, [max[0], min[1]], *max, [min[0], max[1]], *min];
                polyline_distance(path, &outline)
            }
        }
        // Two lines were measured above.
        Feature::Crack { .. } | Feature::Decoy { .. } => return None,
    };
    Some((gap - half).max(0.0))
}

/// The smallest [`feature_gap_mm`] of a scene: how close its lines come to anything else, mm;
/// `None` with at most one line and nothing else.
pub fn clearance_mm(scene: &Scene) -> Option<f64> {
    let f = &scene.features;
    (0..f.len())
        .flat_map(|i| (i + 1..f.len()).filter_map(move |j| feature_gap_mm(&f[i], &f[j])))
        .reduce(f64::min)
}

/// Whether the stroke `a`–`b` crosses (or touches) the feature `f`.
pub(crate) fn stroke_meets(a: [f64; 2], b: [f64; 2], f: &Feature) -> bool {
    let polyline = |path: &[[f64; 2]], half_width: f64| {
        path.windows(2)
            .any(|s| segment_distance(a, b, s[0], s[1]) <= half_width)
    };
    match f {
        Feature::Crack { path, width_mm, .. } | Feature::Decoy { path, width_mm, .. } => {
            polyline(path, width_mm / 2.0)
        }
        Feature::Bump {
            centre, radius_mm, ..
        } => distance_to_polyline(&[a, b], *centre) < *radius_mm,
        Feature::Screw {
            centre,
            head_diameter_mm,
            ..
        } => distance_to_polyline(&[a, b], *centre) < head_diameter_mm / 2.0,
        Feature::Wavy { min, max, .. } => {
            // Points every 0.5 mm along the stroke, inside the patch's rectangle.
            let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.5).ceil().max(1.0) as usize;
            (0..=n).any(|k| {
                let t = k as f64 / n as f64;
                in_rectangle(
                    *min,
                    *max,
                    [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])],
                )
            })
        }
    }
}
