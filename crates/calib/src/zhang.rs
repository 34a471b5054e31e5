//! Zhang's closed-form start (Z. Zhang, "A flexible new technique for camera calibration",
//! IEEE TPAMI 22(11), 2000): each view's homography `H = K [r1 r2 t]` gives two constraints on
//! `B = K⁻ᵀ K⁻¹` (`h1ᵀ B h2 = 0`, `h1ᵀ B h1 = h2ᵀ B h2`); with zero skew as one more, three views
//! tilted differently determine `B`, hence `K`. Each view's pose then follows from `K⁻¹ H`.
//! No distortion here: [`crate::refine`] adds it.

use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};

use crate::lens::Intrinsics;
use crate::pose::Pose;

/// The row `v_ij` of Zhang's system for columns `i`, `j` of `h`.
fn v(h: &Matrix3<f64>, i: usize, j: usize) -> [f64; 6] {
    let (a, b) = (h.column(i), h.column(j));
    [
        a[0] * b[0],
        a[0] * b[1] + a[1] * b[0],
        a[1] * b[1],
        a[2] * b[0] + a[0] * b[2],
        a[2] * b[1] + a[1] * b[2],
        a[2] * b[2],
    ]
}

/// The intrinsics from the views' homographies (pixel ← target plane), or why they are not
/// determined. Pixels are first scaled by `scale` about `centre` so that `B`'s entries are of
/// one magnitude.
pub fn intrinsics(
    homographies: &[Matrix3<f64>],
    centre: [f64; 2],
    scale: f64,
) -> Result<Intrinsics, String> {
    let n = Matrix3::new(
        scale,
        0.0,
        -scale * centre[0],
        0.0,
        scale,
        -scale * centre[1],
        0.0,
        0.0,
        1.0,
    );
    let mut a = DMatrix::<f64>::zeros(2 * homographies.len() + 1, 6);
    for (k, h) in homographies.iter().enumerate() {
        // Each view's constraints are homogeneous in its H: scale it to unit norm so every view
        // weighs alike.
        let h = n * h;
        let h = h / h.norm();
        let v12 = v(&h, 0, 1);
        let v11 = v(&h, 0, 0);
        let v22 = v(&h, 1, 1);
        a.row_mut(2 * k).copy_from_slice(&v12);
        let diff: Vec<f64> = v11.iter().zip(&v22).map(|(x, y)| x - y).collect();
        a.row_mut(2 * k + 1).copy_from_slice(&diff);
    }
    // Zero skew: B12 = 0, weighted like a view's rows.
    let rows = 2 * homographies.len();
    let weight = (0..rows).map(|r| a.row(r).norm()).sum::<f64>() / rows as f64;
    a[(rows, 1)] = weight;
    let svd = a.svd(false, true);
    let v_t = svd.v_t.ok_or("the views' system could not be solved")?;
    let s = &svd.singular_values;
    let mut order: Vec<usize> = (0..s.len()).collect();
    order.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    if s[order[1]] < 1e-6 * s[order[5]] {
        return Err(
            "the views are too alike (tilt the target differently in each: \
                    at least 3 views, 10–45° from face-on, in different directions)"
                .into(),
        );
    }
    let mut b = v_t.row(order[0]).transpose();
    if b[0] < 0.0 {
        b = -b;
    }
    let (b11, b12, b22, b13, b23, b33) = (b[0], b[1], b[2], b[3], b[4], b[5]);
    let den = b11 * b22 - b12 * b12;
    let cy = (b12 * b13 - b11 * b23) / den;
    let lambda = b33 - (b13 * b13 + cy * (b12 * b13 - b11 * b23)) / b11;
    let fx = (lambda / b11).sqrt();
    let fy = (lambda * b11 / den).sqrt();
    let skew = -b12 * fx * fx * fy / lambda;
    let cx = skew * cy / fy - b13 * fx * fx / lambda;
    if ![fx, fy, cx, cy].iter().all(|v| v.is_finite()) || den <= 0.0 {
        return Err("the views do not give a real camera (are the points matched right?)".into());
    }
    // Back to pixels.
    Ok(Intrinsics {
        fx: fx / scale,
        fy: fy / scale,
        cx: cx / scale + centre[0],
        cy: cy / scale + centre[1],
    })
}

/// The pose of a view's target from its homography and the intrinsics (target in front).
pub fn pose(h: &Matrix3<f64>, k: &Intrinsics) -> Option<Pose> {
    let k_inv = Matrix3::new(k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0).try_inverse()?;
    let m = k_inv * h;
    let (a1, a2, a3) = (
        m.column(0).into_owned(),
        m.column(1).into_owned(),
        m.column(2).into_owned(),
    );
    let mut lambda = 1.0 / a1.norm();
    if (lambda * a3).z < 0.0 {
        lambda = -lambda;
    }
    let r1 = lambda * a1;
    let r2 = lambda * a2;
    let r3 = r1.cross(&r2);
    let r = Matrix3::from_columns(&[r1, r2, r3]);
    // The nearest rotation (the columns are only nearly orthonormal with noise).
    let svd = r.svd(true, true);
    let mut rot = svd.u? * svd.v_t?;
    if rot.determinant() < 0.0 {
        rot = -rot;
    }
    let t: Vector3<f64> = lambda * a3;
    Some(Pose::new(&Rotation3::from_matrix_unchecked(rot), t))
}
