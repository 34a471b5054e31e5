//! Levenberg–Marquardt over the lens and the views' poses, minimising the squared reprojection
//! error in pixels. The Jacobian is by central differences (each pose only touches its own
//! view's residuals); the damping is Marquardt's (`JᵀJ + μ diag(JᵀJ)`).

use nalgebra::{DMatrix, DVector, Vector3};

use crate::lens::{Distortion, Intrinsics, Lens};
use crate::pose::Pose;
use crate::CalibError;

/// Parameters of the lens: fx, fy, cx, cy, k1, k2, p1, p2, k3.
const LENS_PARAMS: usize = 9;
const POSE_PARAMS: usize = 6;

/// Matched points of one view: target (mm, z = 0) and image (pixels).
#[derive(Debug, Clone, Copy)]
pub struct Points<'a> {
    /// Target points.
    pub target: &'a [[f64; 2]],
    /// Their pixels.
    pub image: &'a [[f64; 2]],
}

/// Which lens parameters move (in the order of [`LENS_PARAMS`]); the others stay as given.
pub type Free = [bool; LENS_PARAMS];

/// Every lens parameter but k3.
pub const ALL_BUT_K3: Free = [true, true, true, true, true, true, true, true, false];
/// The lens fixed: only the poses move.
pub const POSES_ONLY: Free = [false; LENS_PARAMS];

fn lens_of(p: &[f64]) -> Lens {
    Lens {
        intrinsics: Intrinsics {
            fx: p[0],
            fy: p[1],
            cx: p[2],
            cy: p[3],
        },
        distortion: Distortion::from_array([p[4], p[5], p[6], p[7], p[8]]),
    }
}

fn pose_of(p: &[f64]) -> Pose {
    Pose {
        rotation: [p[0], p[1], p[2]],
        translation: [p[3], p[4], p[5]],
    }
}

/// Residuals (projected − observed, u then v) of one view; a point behind the camera counts as
/// 1e6 px off.
fn view_residuals(lens: &Lens, pose: &Pose, view: &Points, out: &mut [f64]) {
    for (i, (t, uv)) in view.target.iter().zip(view.image).enumerate() {
        let p = pose.apply(Vector3::new(t[0], t[1], 0.0));
        let [u, v] = lens.project(p).unwrap_or([1e6, 1e6]);
        out[2 * i] = u - uv[0];
        out[2 * i + 1] = v - uv[1];
    }
}

struct Problem<'a> {
    views: &'a [Points<'a>],
    /// Offset of each view's residuals.
    offsets: Vec<usize>,
    rows: usize,
    free: Free,
}

impl Problem<'_> {
    fn residuals(&self, params: &[f64]) -> DVector<f64> {
        let lens = lens_of(params);
        let mut r = DVector::zeros(self.rows);
        for (k, view) in self.views.iter().enumerate() {
            let pose = pose_of(&params[LENS_PARAMS + POSE_PARAMS * k..]);
            let o = self.offsets[k];
            view_residuals(
                &lens,
                &pose,
                view,
                &mut r.as_mut_slice()[o..o + 2 * view.target.len()],
            );
        }
        r
    }

    /// Columns of the parameters that move.
    fn columns(&self) -> Vec<usize> {
        let lens = (0..LENS_PARAMS).filter(|&j| self.free[j]);
        lens.chain(LENS_PARAMS..LENS_PARAMS + POSE_PARAMS * self.views.len())
            .collect()
    }

    fn jacobian(&self, params: &[f64], columns: &[usize]) -> DMatrix<f64> {
        let mut j = DMatrix::zeros(self.rows, columns.len());
        let mut p = params.to_vec();
        for (c, &col) in columns.iter().enumerate() {
            let h = 1e-6 * params[col].abs().max(1.0);
            let original = p[col];
            if col < LENS_PARAMS {
                p[col] = original + h;
                let plus = self.residuals(&p);
                p[col] = original - h;
                let minus = self.residuals(&p);
                j.set_column(c, &((plus - minus) / (2.0 * h)));
            } else {
                // A pose parameter: only its view's rows change.
                let k = (col - LENS_PARAMS) / POSE_PARAMS;
                let view = &self.views[k];
                let (o, n) = (self.offsets[k], 2 * view.target.len());
                let lens = lens_of(&p);
                let base = LENS_PARAMS + POSE_PARAMS * k;
                let mut plus = vec![0.0; n];
                let mut minus = vec![0.0; n];
                p[col] = original + h;
                view_residuals(&lens, &pose_of(&p[base..]), view, &mut plus);
                p[col] = original - h;
                view_residuals(&lens, &pose_of(&p[base..]), view, &mut minus);
                for i in 0..n {
                    j[(o + i, c)] = (plus[i] - minus[i]) / (2.0 * h);
                }
            }
            p[col] = original;
        }
        j
    }
}

/// The refined lens and poses, and the RMS reprojection error (px) over all points.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The lens.
    pub lens: Lens,
    /// One pose per view.
    pub poses: Vec<Pose>,
    /// Root mean square of the point errors, pixels.
    pub rms_px: f64,
}

/// Refines `lens` (its `free` parameters) and `poses` against `views`.
pub fn refine(
    lens: &Lens,
    poses: &[Pose],
    views: &[Points],
    free: Free,
) -> Result<Refined, CalibError> {
    let mut offsets = Vec::with_capacity(views.len());
    let mut rows = 0;
    for v in views {
        offsets.push(rows);
        rows += 2 * v.target.len();
    }
    let problem = Problem {
        views,
        offsets,
        rows,
        free,
    };
    let k = &lens.intrinsics;
    let mut params = vec![k.fx, k.fy, k.cx, k.cy];
    params.extend(lens.distortion.to_array());
    for p in poses {
        params.extend(p.rotation);
        params.extend(p.translation);
    }
    let columns = problem.columns();
    let mut r = problem.residuals(&params);
    let mut cost = r.norm_squared();
    let mut mu = 1e-3;
    for _ in 0..200 {
        let j = problem.jacobian(&params, &columns);
        let jt = j.transpose();
        let jtj = &jt * &j;
        let g = &jt * &r;
        let mut improved = false;
        while mu < 1e12 {
            let mut a = jtj.clone();
            for d in 0..a.nrows() {
                a[(d, d)] += mu * jtj[(d, d)].max(1e-12);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&(-&g))) else {
                mu *= 10.0;
                continue;
            };
            let mut trial = params.clone();
            for (c, &col) in columns.iter().enumerate() {
                trial[col] += step[c];
            }
            let r_trial = problem.residuals(&trial);
            let trial_cost = r_trial.norm_squared();
            if trial_cost.is_finite() && trial_cost < cost {
                let gain = (cost - trial_cost) / cost.max(1e-300);
                params = trial;
                r = r_trial;
                cost = trial_cost;
                mu = (mu / 3.0).max(1e-12);
                improved = true;
                if gain < 1e-12 {
                    return Ok(finish(&params, views.len(), cost, rows));
                }
                break;
            }
            mu *= 4.0;
        }
        if !improved {
            break;
        }
    }
    if !cost.is_finite() {
        return Err(CalibError::Diverged {
            reason: "the reprojection error is not finite".into(),
        });
    }
    Ok(finish(&params, views.len(), cost, rows))
}

fn finish(params: &[f64], views: usize, cost: f64, rows: usize) -> Refined {
    Refined {
        lens: lens_of(params),
        poses: (0..views)
            .map(|k| pose_of(&params[LENS_PARAMS + POSE_PARAMS * k..]))
            .collect(),
        rms_px: (cost / (rows / 2).max(1) as f64).sqrt(),
    }
}
