//! Plane geometry on surface points (`[x, y]`, mm), shared by the simulator and the mission.

/// A point on the surface, mm.
pub type Point = [f64; 2];

/// Euclidean distance between two points.
pub fn distance(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to the polyline `path` (to the point itself for a single point; infinite
/// for an empty path).
pub fn distance_to_polyline(path: &[Point], p: Point) -> f64 {
    match path {
        [] => f64::INFINITY,
        [a] => distance(*a, p),
        _ => path
            .windows(2)
            .map(|s| distance_to_segment(s[0], s[1], p))
            .fold(f64::INFINITY, f64::min),
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn distance_to_segment(a: Point, b: Point, p: Point) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    distance([a[0] + t * ab[0], a[1] + t * ab[1]], p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_a_polyline_are_to_its_nearest_segment_or_end() {
        let path = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]];
        assert_eq!(distance_to_polyline(&path, [5.0, 3.0]), 3.0);
        assert_eq!(distance_to_polyline(&path, [13.0, 5.0]), 3.0);
        assert_eq!(distance_to_polyline(&path, [-3.0, -4.0]), 5.0);
        assert_eq!(distance_to_polyline(&path[..1], [3.0, 4.0]), 5.0);
        assert_eq!(distance_to_polyline(&[], [0.0, 0.0]), f64::INFINITY);
        // A segment of no length is its point.
        assert_eq!(distance_to_segment([1.0, 1.0], [1.0, 1.0], [4.0, 5.0]), 5.0);
    }
}
