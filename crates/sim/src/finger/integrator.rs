//! The integrators that carry the finger from output sample to output sample: two-stage
//! L-stable SDIRK (the default), backward Euler, adaptive Dormand–Prince and symplectic Euler.

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use super::model::{ArmPath, FingerModel, State, STATE};
use crate::SimError;

type Vec6 = SVector<f64, STATE>;
type Mat6 = SMatrix<f64, STATE, STATE>;

/// A time-stepping method for the finger.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum Integrator {
    /// Two-stage L-stable SDIRK (Alexander, order 2) with `substeps` steps per output sample and
    /// simplified Newton on a finite-difference Jacobian; a step whose Newton iteration fails
    /// is retried as two half steps. The default.
    Sdirk2 {
        /// Steps per output sample.
        substeps: u32,
    },
    /// Backward Euler (L-stable, order 1), same machinery.
    BackwardEuler {
        /// Steps per output sample.
        substeps: u32,
    },
    /// Explicit Dormand–Prince 5(4) with adaptive steps (error control per output interval).
    DormandPrince {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance (m, m/s).
        atol: f64,
    },
    /// Explicit semi-implicit (symplectic) Euler with a fixed number of sub-steps: unstable on
    /// the stiff contact unless the sub-steps are tiny; kept to show why.
    SymplecticEuler {
        /// Steps per output sample.
        substeps: u32,
    },
}

impl Default for Integrator {
    fn default() -> Self {
        Integrator::Sdirk2 { substeps: 1 }
    }
}

impl Integrator {
    /// Checks the integrator's settings.
    pub fn validate(&self) -> Result<(), SimError> {
        match *self {
            Integrator::Sdirk2 { substeps }
            | Integrator::BackwardEuler { substeps }
            | Integrator::SymplecticEuler { substeps } => {
                if substeps == 0 || substeps > 1_000_000 {
                    return Err(SimError::setting(
                        "integrator.substeps",
                        substeps,
                        "in 1..=1000000",
                    ));
                }
            }
            Integrator::DormandPrince { rtol, atol } => {
                for (name, v) in [("integrator.rtol", rtol), ("integrator.atol", atol)] {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(SimError::setting(
                            name,
                            v,
                            "> 0 (a Dormand-Prince tolerance)",
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// A short label for tables.
    pub fn label(&self) -> String {
        match *self {
            Integrator::Sdirk2 { substeps } => format!("sdirk2 x{substeps}"),
            Integrator::BackwardEuler { substeps } => format!("backward-euler x{substeps}"),
            Integrator::DormandPrince { rtol, .. } => format!("dopri5 rtol {rtol:.0e}"),
            Integrator::SymplecticEuler { substeps } => format!("symplectic-euler x{substeps}"),
        }
    }
}

/// Counters of the work an integrator did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Work {
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Steps taken (accepted).
    pub steps: u64,
    /// Steps rejected (Newton failure or error too large).
    pub rejected: u64,
    /// Tiny steps taken explicitly because Newton could not converge even there.
    pub explicit_fallbacks: u64,
}

/// Integrates a [`FingerModel`] from output sample to output sample.
#[derive(Debug, Clone)]
pub struct Stepper {
    method: Integrator,
    /// Last accepted step of the adaptive method, s.
    h_adaptive: f64,
    /// The factorised Newton matrix `I − a J` of the last implicit step and its `a`: reused by
    /// the next step of the same size (Newton refreshes it where it stalls).
    newton: Option<(f64, NewtonLu)>,
    /// Work done so far.
    pub work: Work,
}

type NewtonLu = nalgebra::LU<f64, nalgebra::Const<STATE>, nalgebra::Const<STATE>>;

fn add(a: &State, b: &State, s: f64) -> State {
    let mut r = *a;
    for k in 0..STATE {
        r[k] += s * b[k];
    }
    r
}

fn finite(y: &State) -> bool {
    y.iter().all(|v| v.is_finite())
}

/// Error scale of the state components (m and m/s).
const SCALE: State = [1e-6, 1e-6, 1e-4, 1e-4, 1e-6, 1e-4];

/// Newton stops when the stage changes by less than this fraction of [`SCALE`] (10 nm, 1 µm/s).
const NEWTON_TOL: f64 = 1e-2;

impl Stepper {
    /// A stepper using `method`.
    pub fn new(method: Integrator) -> Self {
        Stepper {
            method,
            h_adaptive: 1e-4,
            newton: None,
            work: Work::default(),
        }
    }

    /// The method.
    pub fn method(&self) -> Integrator {
        self.method
    }

    /// Advances `y` from `t` to `t + dt`.
    pub fn advance(
        &mut self,
        model: &FingerModel,
        arm: &dyn ArmPath,
        t: f64,
        dt: f64,
        y: &mut State,
    ) -> Result<(), SimError> {
        match self.method {
            Integrator::Sdirk2 { substeps } | Integrator::BackwardEuler { substeps } => {
                let h = dt / substeps as f64;
                for k in 0..substeps {
                    self.implicit_step(model, arm, t + k as f64 * h, h, y, 0)?;
                }
            }
            Integrator::SymplecticEuler { substeps } => {
                let h = dt / substeps as f64;
                for k in 0..substeps {
                    let tk = t + k as f64 * h;
                    let f = model.rhs(tk, y, arm);
                    self.work.rhs_evals += 1;
                    // Velocities first, then positions with the new velocities.
                    for (v, a) in [(2, 2), (3, 3), (5, 5)] {
                        y[v] += h * f[a];
                    }
                    y[0] += h * y[2];
                    y[1] += h * y[3];
                    y[4] += h * y[5];
                    self.work.steps += 1;
                }
                if !finite(y) {
                    return Err(SimError::Integration {
                        t: t + dt,
                        reason: "the explicit step blew up (state not finite)".into(),
                    });
                }
            }
            Integrator::DormandPrince { rtol, atol } => {
                self.dopri(model, arm, t, dt, y, rtol, atol)?;
            }
        }
        Ok(())
    }

    fn jacobian(&mut self, model: &FingerModel, arm: &dyn ArmPath, t: f64, y: &State) -> Mat6 {
        let f0 = model.rhs(t, y, arm);
        let mut j = Mat6::zeros();
        for c in 0..STATE {
            let eps = SCALE[c] * 1e-3;
            let mut yp = *y;
            yp[c] += eps;
            let fp = model.rhs(t, &yp, arm);
            for r in 0..STATE {
                j[(r, c)] = (fp[r] - f0[r]) / eps;
            }
        }
        self.work.rhs_evals += STATE as u64 + 1;
        j
    }

    /// Solves the stage equation `k = f(t, base + a k)` by Newton's method on `I - a J`: the
    /// factorisation `lu` of the step's Jacobian is reused (simplified Newton) and refreshed at
    /// the current iterate when the iteration stalls (a contact switching inside the step).
    #[expect(
        clippy::too_many_arguments,
        reason = "each argument is one the step needs, and a struct would only rename them"
    )]
    fn stage(
        &mut self,
        model: &FingerModel,
        arm: &dyn ArmPath,
        t: f64,
        base: &State,
        a: f64,
        lu: &mut nalgebra::LU<f64, nalgebra::Const<STATE>, nalgebra::Const<STATE>>,
        guess: State,
    ) -> Option<State> {
        let mut k = guess;
        let mut last_err = f64::INFINITY;
        for iter in 0..16 {
            let yk = add(base, &k, a);
            let f = model.rhs(t, &yk, arm);
            self.work.rhs_evals += 1;
            let mut r = Vec6::zeros();
            for i in 0..STATE {
                r[i] = f[i] - k[i];
            }
            let d = lu.solve(&r)?;
            let mut err: f64 = 0.0;
            for i in 0..STATE {
                k[i] += d[i];
                // The change of the stage state a*d, against the error scale.
                err = err.max((a * d[i]).abs() / SCALE[i]);
            }
            if !err.is_finite() {
                return None;
            }
            if err < NEWTON_TOL {
                return Some(k);
            }
            if iter >= 2 && err > 0.5 * last_err {
                // Slow convergence: refresh the Jacobian where the iterate is now.
                let yk = add(base, &k, a);
                let j = self.jacobian(model, arm, t, &yk);
                *lu = (Mat6::identity() - j * a).lu();
            }
            last_err = err;
        }
        None
    }

    fn implicit_step(
        &mut self,
        model: &FingerModel,
        arm: &dyn ArmPath,
        t: f64,
        h: f64,
        y: &mut State,
        depth: u32,
    ) -> Result<(), SimError> {
        let sdirk = matches!(self.method, Integrator::Sdirk2 { .. });
        let gamma = if sdirk {
            1.0 - std::f64::consts::FRAC_1_SQRT_2
        } else {
            1.0
        };
        let a = h * gamma;
        let mut lu = match self.newton.take() {
            Some((cached, lu)) if cached == a => lu,
            _ => {
                let j = self.jacobian(model, arm, t, y);
                (Mat6::identity() - j * a).lu()
            }
        };
        let f0 = model.rhs(t, y, arm);
        self.work.rhs_evals += 1;
        let result = (|| {
            let k1 = self.stage(model, arm, t + gamma * h, y, gamma * h, &mut lu, f0)?;
            if !sdirk {
                return Some(add(y, &k1, h));
            }
            let base = add(y, &k1, (1.0 - gamma) * h);
            let k2 = self.stage(model, arm, t + h, &base, gamma * h, &mut lu, k1)?;
            let mut out = *y;
            for i in 0..STATE {
                out[i] += h * ((1.0 - gamma) * k1[i] + gamma * k2[i]);
            }
            Some(out)
        })();
        match result {
            Some(next) if finite(&next) => {
                *y = next;
                self.work.steps += 1;
                self.newton = Some((a, lu));
                Ok(())
            }
            _ => {
                self.work.rejected += 1;
                if depth >= 16 {
                    // A step this small (tens of ns) is well inside an explicit method's
                    // stability limit even on the stiff contact: where Newton cannot follow a
                    // violent event (a jammed tip chattering on a wall corner), take it with
                    // Heun's method rather than give up.
                    let f0 = model.rhs(t, y, arm);
                    let y1 = add(y, &f0, h);
                    let f1 = model.rhs(t + h, &y1, arm);
                    self.work.rhs_evals += 2;
                    let mut next = *y;
                    for i in 0..STATE {
                        next[i] += 0.5 * h * (f0[i] + f1[i]);
                    }
                    if !finite(&next) {
                        return Err(SimError::Integration {
                            t,
                            reason: format!(
                                "Newton did not converge with a step of {h:.3e} s and the \
                                 explicit fallback is not finite"
                            ),
                        });
                    }
                    *y = next;
                    self.work.explicit_fallbacks += 1;
                    return Ok(());
                }
                self.implicit_step(model, arm, t, h / 2.0, y, depth + 1)?;
                self.implicit_step(model, arm, t + h / 2.0, h / 2.0, y, depth + 1)
            }
        }
    }

    #[expect(
        clippy::too_many_arguments,
        reason = "each argument is one the step needs, and a struct would only rename them"
    )]
    fn dopri(
        &mut self,
        model: &FingerModel,
        arm: &dyn ArmPath,
        t0: f64,
        dt: f64,
        y: &mut State,
        rtol: f64,
        atol: f64,
    ) -> Result<(), SimError> {
        // Dormand–Prince 5(4) tableau.
        const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
        const A: [[f64; 6]; 7] = [
            [0.0; 6],
            [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
            [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
            [
                19372.0 / 6561.0,
                -25360.0 / 2187.0,
                64448.0 / 6561.0,
                -212.0 / 729.0,
                0.0,
                0.0,
            ],
            [
                9017.0 / 3168.0,
                -355.0 / 33.0,
                46732.0 / 5247.0,
                49.0 / 176.0,
                -5103.0 / 18656.0,
                0.0,
            ],
            [
                35.0 / 384.0,
                0.0,
                500.0 / 1113.0,
                125.0 / 192.0,
                -2187.0 / 6784.0,
                11.0 / 84.0,
            ],
        ];
        const B5: [f64; 7] = [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
            0.0,
        ];
        const B4: [f64; 7] = [
            5179.0 / 57600.0,
            0.0,
            7571.0 / 16695.0,
            393.0 / 640.0,
            -92097.0 / 339200.0,
            187.0 / 2100.0,
            1.0 / 40.0,
        ];
        let t_end = t0 + dt;
        let mut t = t0;
        let mut h = self.h_adaptive.min(dt);
        let mut guard = 0u64;
        while t < t_end - 1e-15 {
            guard += 1;
            if guard > 10_000_000 || h < 1e-12 {
                return Err(SimError::Integration {
                    t,
                    reason: format!("Dormand-Prince step size collapsed to {h:.3e} s"),
                });
            }
            let h_try = h.min(t_end - t);
            let mut k = [[0.0; STATE]; 7];
            for s in 0..7 {
                let mut ys = *y;
                for (j, kj) in k.iter().enumerate().take(s) {
                    let a = A[s][j];
                    if a != 0.0 {
                        for i in 0..STATE {
                            ys[i] += h_try * a * kj[i];
                        }
                    }
                }
                k[s] = model.rhs(t + C[s] * h_try, &ys, arm);
            }
            self.work.rhs_evals += 7;
            let mut y5 = *y;
            let mut err: f64 = 0.0;
            for i in 0..STATE {
                let mut d5 = 0.0;
                let mut d4 = 0.0;
                for s in 0..7 {
                    d5 += B5[s] * k[s][i];
                    d4 += B4[s] * k[s][i];
                }
                y5[i] += h_try * d5;
                // atol is in metres for positions; velocities get 100× (m/s against ~mm/s).
                let sc = atol * SCALE[i] / SCALE[0] + rtol * y[i].abs().max(y5[i].abs());
                err = err.max((h_try * (d5 - d4)).abs() / sc);
            }
            if err.is_finite() && err <= 1.0 {
                t += h_try;
                *y = y5;
                self.work.steps += 1;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                h = h_try * fac;
                self.h_adaptive = h;
            } else {
                self.work.rejected += 1;
                let fac = if err.is_finite() {
                    (0.9 * err.powf(-0.2)).clamp(0.1, 0.5)
                } else {
                    0.1
                };
                h = h_try * fac;
            }
        }
        Ok(())
    }
}
