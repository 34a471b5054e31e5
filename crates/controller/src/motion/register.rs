//! Registering the plate: its plane and frame in the arm's base frame from points on it (touched
//! by guarded moves, or jogged to by the operator), as a [`SurfaceFrame`].
//!
//! The first point is the surface frame's origin, the second lies along its +x axis, any more
//! only pin the plane down. The plane is the least-squares fit of all points (the normal is the
//! eigenvector of their scatter with the least eigenvalue); its normal points back along the
//! direction the finger approached from, so that z grows away from the plate as the link
//! expects.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

use crate::motion::frame::SurfaceFrame;

/// Points that cannot give a frame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegisterError {
    /// Fewer than three points.
    #[error("{0} points: at least 3 are needed (origin, a point along +x, one more on the plate)")]
    TooFew(usize),
    /// A point is not finite.
    #[error("point {0} is not finite")]
    NotFinite(usize),
    /// The points do not span a plane (on one line, or the first two too close).
    #[error("the points do not span a plane: {0}")]
    Degenerate(&'static str),
    /// The points lie off any one plane by more than the tolerance.
    #[error("the points lie up to {worst_mm:.2} mm off their best plane (tolerance {tolerance_mm:.2} mm): a touch missed the plate, or the plate is not flat")]
    NotPlanar {
        /// The largest distance of a point from the plane, mm.
        worst_mm: f64,
        /// The tolerance, mm.
        tolerance_mm: f64,
    },
}

/// How far off their plane touched points may lie, mm.
pub const PLANARITY_TOLERANCE_MM: f64 = 0.5;

/// The surface frame from points on the plate (m, base frame) touched moving along `approach`
/// (a direction in the base frame, towards the plate).
pub fn frame_from_points(
    points: &[[f64; 3]],
    approach: [f64; 3],
) -> Result<SurfaceFrame, RegisterError> {
    if points.len() < 3 {
        return Err(RegisterError::TooFew(points.len()));
    }
    if let Some(i) = points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        return Err(RegisterError::NotFinite(i + 1));
    }
    let v: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
    let centroid = v.iter().sum::<Vector3<f64>>() / v.len() as f64;
    let scatter = v.iter().fold(Matrix3::zeros(), |m, p| {
        let d = p - centroid;
        m + d * d.transpose()
    });
    let eigen = scatter.symmetric_eigen();
    let (order, _) =
        eigen
            .eigenvalues
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |(bi, bv), (i, &e)| if e < bv { (i, e) } else { (bi, bv) },
            );
    let mut sorted: Vec<f64> = eigen.eigenvalues.iter().copied().collect();
    sorted.sort_by(f64::total_cmp);
    if sorted[1] < 1e-12 {
        return Err(RegisterError::Degenerate("they lie on one line"));
    }
    let mut normal: Vector3<f64> = eigen.eigenvectors.column(order).into_owned().normalize();
    if normal.dot(&Vector3::from(approach)) > 0.0 {
        normal = -normal;
    }
    let worst = v
        .iter()
        .map(|p| (p - centroid).dot(&normal).abs())
        .fold(0.0, f64::max);
    if worst * 1e3 > PLANARITY_TOLERANCE_MM {
        return Err(RegisterError::NotPlanar {
            worst_mm: worst * 1e3,
            tolerance_mm: PLANARITY_TOLERANCE_MM,
        });
    }
    let project = |p: &Vector3<f64>| p - normal * (p - centroid).dot(&normal);
    let origin = project(&v[0]);
    let along = project(&v[1]) - origin;
    if along.norm() < 5e-3 {
        return Err(RegisterError::Degenerate(
            "the first two points are under 5 mm apart",
        ));
    }
    let x = along.normalize();
    let y = normal.cross(&x);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, y, normal]));
    let q = UnitQuaternion::from_rotation_matrix(&r);
    Ok(SurfaceFrame {
        origin_m: [origin.x, origin.y, origin.z],
        rotation_xyzw: [q.i, q.j, q.k, q.w],
        ..SurfaceFrame::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A plate tilted and offset by drawn amounts, touched at drawn points with 20 µm of
        /// noise: the fitted plane's normal is within 0.2° and its offset within 0.2 mm.
        #[test]
        fn a_tilted_offset_plate_is_found_within_a_fifth_of_a_millimetre_and_degree(
            tilt in prop::array::uniform3(-0.4f64..0.4),
            offset in prop::array::uniform3(-0.3f64..0.3),
            spots in prop::collection::vec(prop::array::uniform2(0.0f64..0.2), 3..8),
            noise in prop::collection::vec(-2e-5f64..2e-5, 8),
        ) {
            let truth = SurfaceFrame {
                origin_m: offset,
                rotation_xyzw: {
                    let q = UnitQuaternion::from_euler_angles(tilt[0], tilt[1], tilt[2]);
                    [q.i, q.j, q.k, q.w]
                },
                ..SurfaceFrame::default()
            };
            let mut at: Vec<[f64; 2]> = vec![[0.0, 0.0], [0.15, 0.0]];
            at.extend(spots.iter().map(|s| [s[0], s[1] * 0.5 + 0.02]));
            let points: Vec<[f64; 3]> = at
                .iter()
                .zip(noise.iter().cycle())
                .map(|(s, n)| truth.to_base([s[0] * 1e3, s[1] * 1e3, n * 1e3]))
                .collect();
            let approach = [0, 1, 2].map(|k| -truth.normal()[k]);
            let found = frame_from_points(&points, approach).expect("frame");
            let (n, m) = (Vector3::from(found.normal()), Vector3::from(truth.normal()));
            let angle = n.angle(&m).to_degrees();
            prop_assert!(angle < 0.2, "normal off by {angle}°");
            // The plane's offset: the found origin's height above the true plane.
            let h = truth.to_surface(found.origin_m)[2].abs();
            prop_assert!(h < 0.2, "plane off by {h} mm");
            // And the frame maps the touched points to z ≈ 0, the origin to (0, 0).
            let o = found.to_surface(points[0]);
            prop_assert!(o[0].hypot(o[1]) < 0.2, "{o:?}");
        }
    }

    #[test]
    fn too_few_points_a_line_or_a_missed_touch_are_named() {
        let flat = |x: f64, y: f64, z: f64| [x, y, z];
        let down = [0.0, 0.0, -1.0];
        assert_eq!(
            frame_from_points(&[flat(0.0, 0.0, 0.0), flat(0.1, 0.0, 0.0)], down),
            Err(RegisterError::TooFew(2))
        );
        let line = [
            flat(0.0, 0.0, 0.0),
            flat(0.1, 0.0, 0.0),
            flat(0.2, 0.0, 0.0),
        ];
        assert!(matches!(
            frame_from_points(&line, down),
            Err(RegisterError::Degenerate(_))
        ));
        let missed = [
            flat(0.0, 0.0, 0.0),
            flat(0.1, 0.0, 0.0),
            flat(0.0, 0.1, 0.0),
            flat(0.1, 0.1, 0.004),
        ];
        let e = frame_from_points(&missed, down).unwrap_err();
        assert!(e.to_string().contains("off their best plane"), "{e}");
        // Level points touched from above: z up, x along the first two.
        let f = frame_from_points(
            &[
                flat(0.3, 0.1, 0.02),
                flat(0.4, 0.1, 0.02),
                flat(0.3, 0.2, 0.02),
            ],
            down,
        )
        .expect("frame");
        let n = f.normal();
        assert!((n[2] - 1.0).abs() < 1e-9, "{n:?}");
        let p = f.to_surface([0.35, 0.15, 0.02]);
        assert!(
            (p[0] - 50.0).abs() < 1e-6 && (p[1] - 50.0).abs() < 1e-6,
            "{p:?}"
        );
    }
}
