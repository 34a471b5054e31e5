//! The homography from a target's plane (mm) to the image (pixels) of one view: the normalised
//! DLT (Hartley), solved by SVD.

use crackbot_imaging::homography::normalisation;
use nalgebra::{DMatrix, Matrix3};

fn apply(m: &Matrix3<f64>, p: [f64; 2]) -> [f64; 2] {
    let v = m * nalgebra::Vector3::new(p[0], p[1], 1.0);
    [v.x / v.z, v.y / v.z]
}

/// `H` with `pixel ~ H (X, Y, 1)ᵀ`, scaled to unit Frobenius norm, from at least 4 pairs; `None`
/// when the points do not determine it (fewer than 4, coincident, all on one line).
pub fn fit(target: &[[f64; 2]], image: &[[f64; 2]]) -> Option<Matrix3<f64>> {
    if target.len() < 4 || target.len() != image.len() {
        return None;
    }
    let t = normalisation(target)?;
    let u = normalisation(image)?;
    let mut a = DMatrix::<f64>::zeros(2 * target.len(), 9);
    for (i, (p, q)) in target.iter().zip(image).enumerate() {
        let [x, y] = apply(&t, *p);
        let [u_, v] = apply(&u, *q);
        a.row_mut(2 * i)
            .copy_from_slice(&[-x, -y, -1.0, 0.0, 0.0, 0.0, u_ * x, u_ * y, u_]);
        a.row_mut(2 * i + 1)
            .copy_from_slice(&[0.0, 0.0, 0.0, -x, -y, -1.0, v * x, v * y, v]);
    }
    // The null vector: the right singular vector of the smallest singular value. Unique only
    // when the second smallest is clearly above zero.
    let svd = a.svd(false, true);
    let v_t = svd.v_t?;
    let s = &svd.singular_values;
    let mut order: Vec<usize> = (0..s.len()).collect();
    order.sort_by(|&i, &j| s[i].total_cmp(&s[j]));
    if s.len() < 9 || s[order[1]] < 1e-7 * s[order[s.len() - 1]] {
        return None;
    }
    let h = v_t.row(order[0]);
    let hn = Matrix3::new(h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]);
    let h = u.try_inverse()? * hn * t;
    let norm = h.norm();
    (norm > 0.0 && norm.is_finite()).then(|| h / norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_known_homography_is_recovered() {
        let truth = Matrix3::new(2.0, 0.1, 300.0, -0.05, 1.9, 200.0, 1e-4, -2e-4, 1.0);
        let target: Vec<[f64; 2]> = (0..20)
            .map(|i| [f64::from(i % 5) * 30.0, f64::from(i / 5) * 30.0])
            .collect();
        let image: Vec<[f64; 2]> = target.iter().map(|p| apply(&truth, *p)).collect();
        let h = fit(&target, &image).expect("a fit");
        for (p, q) in target.iter().zip(&image) {
            let r = apply(&h, *p);
            assert!((r[0] - q[0]).hypot(r[1] - q[1]) < 1e-8);
        }
    }

    #[test]
    fn points_on_one_line_give_nothing() {
        let target: Vec<[f64; 2]> = (0..6).map(|i| [f64::from(i), 2.0 * f64::from(i)]).collect();
        assert!(fit(&target, &target).is_none());
        assert!(fit(&target[..3], &target[..3]).is_none());
    }
}
