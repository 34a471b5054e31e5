//! Lines on the plate: a direction between two points and how far a pose lies along a line.

/// The unit vector from `a` towards `b` (mm on the plate).
pub(crate) fn unit(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l = d[0].hypot(d[1]).max(1e-9);
    [d[0] / l, d[1] / l]
}

/// How far the arm's pose `p` is along the line from `a` with unit direction `u`, mm.
pub(crate) fn along(a: [f64; 2], u: [f64; 2], p: [f64; 3]) -> f64 {
    (p[0] - a[0]) * u[0] + (p[1] - a[1]) * u[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pose_is_placed_along_a_line_by_its_projection() {
        let u = unit([10.0, 10.0], [10.0, 30.0]);
        assert_eq!(u, [0.0, 1.0]);
        assert_eq!(along([10.0, 10.0], u, [12.0, 15.0, 3.0]), 5.0);
        assert_eq!(along([10.0, 10.0], u, [10.0, 5.0, 0.0]), -5.0);
        // A line of no length has no direction, and places nothing.
        assert_eq!(unit([1.0, 1.0], [1.0, 1.0]), [0.0, 0.0]);
    }
}
