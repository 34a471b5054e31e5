//! The finger's mechanics: its parameters, the rolling envelope the tip rides on, the arm's
//! path, and the equations of motion (see the [module docs](super)).

use serde::{Deserialize, Serialize};

use crate::surface::Profile;
use crate::SimError;

/// Size of the state vector.
pub const STATE: usize = 6;
/// The state: `[x_t, z_t, ẋ_t, ż_t, z_b, ż_b]`, SI units.
pub type State = [f64; STATE];

const G: f64 = 9.81;

/// Mechanical parameters of the finger.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FingerParams {
    /// Radius of the spherical tip, mm.
    pub tip_radius_mm: f64,
    /// Mass of the tip, g.
    pub tip_mass_g: f64,
    /// Mass of the sensor body resting on the surface, g (the paper: ~200 g).
    pub body_mass_g: f64,
    /// Lateral stiffness of the finger's compliant part, N/mm.
    pub lateral_stiffness_n_mm: f64,
    /// Normal stiffness of the finger's compliant part, N/mm.
    pub normal_stiffness_n_mm: f64,
    /// Damping ratio of the lateral mode (tip mass on the lateral spring).
    pub lateral_damping_ratio: f64,
    /// Damping ratio of the normal mode (tip mass on the normal spring).
    pub normal_damping_ratio: f64,
    /// Contact penalty stiffness, N/m (stiff: ≥ 1e5).
    pub contact_stiffness_n_m: f64,
    /// Damping ratio of the contact mode (tip mass on the contact stiffness).
    pub contact_damping_ratio: f64,
    /// Coulomb friction coefficient between tip and surface.
    pub friction: f64,
    /// Sliding speed below which friction is regularised, mm/s.
    pub friction_velocity_mm_s: f64,
    /// Viscous damping of the arm's vertical axis carrying the body, N·s/m.
    pub arm_damping_n_s_m: f64,
    /// How far the tip can lag or lead the body before the compliant part meets its end stop,
    /// mm; beyond it the arm drags the tip through a spring [`END_STOP_FACTOR`] times stiffer,
    /// up to [`END_STOP_MAX_FORCE_N`] (a position-controlled arm drags the finger out of a
    /// crack whose rim the compliant part alone cannot pull it over). Absent: no end stop.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lateral_travel_mm: Option<f64>,
}

/// Stiffness of the lateral end stop relative to the compliant part's.
pub const END_STOP_FACTOR: f64 = 50.0;

/// Most the end stop pushes, N (the arm's force limit): against a wall the tip cannot climb
/// (taller than its radius, or steeper than friction allows) the tip stays and the arm goes on,
/// rather than the stop's force growing without bound until the contact gives way.
pub const END_STOP_MAX_FORCE_N: f64 = 20.0;

impl Default for FingerParams {
    fn default() -> Self {
        FingerParams {
            tip_radius_mm: 4.435,
            tip_mass_g: 2.0,
            body_mass_g: 200.0,
            lateral_stiffness_n_mm: 0.586,
            normal_stiffness_n_mm: 2.0,
            lateral_damping_ratio: 0.7,
            normal_damping_ratio: 0.7,
            contact_stiffness_n_m: 2e5,
            contact_damping_ratio: 0.3,
            friction: 0.330,
            friction_velocity_mm_s: 0.5,
            arm_damping_n_s_m: 8.0,
            lateral_travel_mm: None,
        }
    }
}

impl FingerParams {
    /// Checks every parameter, naming the first bad one.
    pub fn validate(&self) -> Result<(), SimError> {
        let positive = [
            ("sensor.finger.tip_radius_mm", self.tip_radius_mm),
            ("sensor.finger.tip_mass_g", self.tip_mass_g),
            ("sensor.finger.body_mass_g", self.body_mass_g),
            (
                "sensor.finger.lateral_stiffness_n_mm",
                self.lateral_stiffness_n_mm,
            ),
            (
                "sensor.finger.normal_stiffness_n_mm",
                self.normal_stiffness_n_mm,
            ),
            (
                "sensor.finger.contact_stiffness_n_m",
                self.contact_stiffness_n_m,
            ),
            (
                "sensor.finger.friction_velocity_mm_s",
                self.friction_velocity_mm_s,
            ),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(SimError::setting(name, v, "> 0"));
            }
        }
        if let Some(t) = self.lateral_travel_mm {
            if !(t.is_finite() && t > 0.0) {
                return Err(SimError::setting(
                    "sensor.finger.lateral_travel_mm",
                    t,
                    "> 0 mm (or left out)",
                ));
            }
        }
        if self.tip_radius_mm > 50.0 {
            return Err(SimError::setting(
                "sensor.finger.tip_radius_mm",
                self.tip_radius_mm,
                "at most 50 mm",
            ));
        }
        let non_negative = [
            (
                "sensor.finger.lateral_damping_ratio",
                self.lateral_damping_ratio,
            ),
            (
                "sensor.finger.normal_damping_ratio",
                self.normal_damping_ratio,
            ),
            (
                "sensor.finger.contact_damping_ratio",
                self.contact_damping_ratio,
            ),
            ("sensor.finger.friction", self.friction),
            ("sensor.finger.arm_damping_n_s_m", self.arm_damping_n_s_m),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::setting(name, v, "≥ 0"));
            }
        }
        Ok(())
    }
}

/// The rolling envelope of a spherical tip over a profile, tabulated with its slope.
#[derive(Debug, Clone)]
pub struct Envelope {
    /// Spacing, m.
    step: f64,
    /// Height of the sphere's lowest point, m.
    height: Vec<f64>,
    /// Slope `de/dx`, clamped to ±[`MAX_SLOPE`].
    slope: Vec<f64>,
    /// Reflectivity along the line (copied from the profile).
    reflectivity: Vec<f64>,
    /// Surface height itself (for the proximity fibre), m.
    surface: Vec<f64>,
}

/// Penetration over which the contact damping fades in, m.
const CONTACT_FADE: f64 = 1e-6;

/// Largest envelope slope (about 87°): walls steeper than this are treated as this steep (the
/// envelope is raised there, so the tip never enters the surface), which keeps the contact
/// force and its Jacobian finite.
pub const MAX_SLOPE: f64 = 20.0;

impl Envelope {
    /// The envelope of a sphere of radius `radius_mm` rolling over `profile`.
    pub fn new(profile: &Profile, radius_mm: f64) -> Self {
        let n = profile.height.len();
        let step_mm = profile.step_mm;
        let reach = (radius_mm / step_mm).floor() as isize;
        // Offsets and their sphere heights, computed once.
        let cap: Vec<(isize, f64)> = (-reach..=reach)
            .map(|k| {
                let u = k as f64 * step_mm;
                (k, (radius_mm * radius_mm - u * u).max(0.0).sqrt())
            })
            .collect();
        let mut env = vec![0.0; n];
        for (i, e) in env.iter_mut().enumerate() {
            let mut best = f64::NEG_INFINITY;
            for &(k, c) in &cap {
                let j = (i as isize + k).clamp(0, n as isize - 1) as usize;
                let v = profile.height[j] + c;
                if v > best {
                    best = v;
                }
            }
            *e = (best - radius_mm) * 1e-3;
        }
        let step = step_mm * 1e-3;
        // Limit the envelope's steepness to MAX_SLOPE by raising it (never lowering it) where it
        // drops or rises faster: a wall taller than the tip's radius becomes an 87° ramp, which
        // keeps the contact force and its Jacobian finite.
        let max_rise = MAX_SLOPE * step;
        for i in 1..n {
            env[i] = env[i].max(env[i - 1] - max_rise);
        }
        for i in (0..n.saturating_sub(1)).rev() {
            env[i] = env[i].max(env[i + 1] - max_rise);
        }
        let slope = (0..n)
            .map(|i| {
                let a = env[i.saturating_sub(1)];
                let b = env[(i + 1).min(n - 1)];
                let span = ((i + 1).min(n - 1) - i.saturating_sub(1)).max(1) as f64 * step;
                ((b - a) / span).clamp(-MAX_SLOPE, MAX_SLOPE)
            })
            .collect();
        Envelope {
            step,
            height: env,
            slope,
            reflectivity: profile.reflectivity.clone(),
            surface: profile.height.iter().map(|h| h * 1e-3).collect(),
        }
    }

    /// Envelope height and slope at `x` metres along the line: a C¹ cubic Hermite interpolant
    /// of the tabulated heights and slopes, and its exact derivative (so the contact force is
    /// the gradient of the contact energy and the contact does no work of its own).
    #[inline]
    pub fn at(&self, x: f64) -> (f64, f64) {
        let last = self.height.len() - 1;
        if last == 0 {
            return (self.height[0], 0.0);
        }
        let u = (x / self.step).clamp(0.0, last as f64);
        let k = (u as usize).min(last - 1);
        let t = u - k as f64;
        let h = self.step;
        let (e0, e1) = (self.height[k], self.height[k + 1]);
        let (s0, s1) = (self.slope[k] * h, self.slope[k + 1] * h);
        let t2 = t * t;
        let t3 = t2 * t;
        let e = (2.0 * t3 - 3.0 * t2 + 1.0) * e0
            + (t3 - 2.0 * t2 + t) * s0
            + (-2.0 * t3 + 3.0 * t2) * e1
            + (t3 - t2) * s1;
        let de = (6.0 * t2 - 6.0 * t) * e0
            + (3.0 * t2 - 4.0 * t + 1.0) * s0
            + (-6.0 * t2 + 6.0 * t) * e1
            + (3.0 * t2 - 2.0 * t) * s1;
        // Outside the table the envelope is continued flat.
        let inside = x > 0.0 && x < last as f64 * h;
        (e, if inside { de / h } else { 0.0 })
    }

    /// Surface height at `x` metres along the line, m.
    #[inline]
    pub fn surface_at(&self, x: f64) -> f64 {
        Profile::sample(&self.surface, self.step, x)
    }

    /// Reflectivity at `x` metres along the line.
    #[inline]
    pub fn reflectivity_at(&self, x: f64) -> f64 {
        Profile::sample(&self.reflectivity, self.step, x)
    }

    /// Length of the line, m.
    pub fn length(&self) -> f64 {
        self.step * (self.height.len() - 1) as f64
    }
}

/// Where the arm puts the sensor body along the line at time `t`: position and velocity, m and
/// m/s.
pub trait ArmPath {
    /// `(x_b, ẋ_b)` at `t` seconds.
    fn at(&self, t: f64) -> (f64, f64);
}

/// The arm standing still at `x`, m.
#[derive(Debug, Clone, Copy)]
pub struct Still(pub f64);

impl ArmPath for Still {
    fn at(&self, _t: f64) -> (f64, f64) {
        (self.0, 0.0)
    }
}

/// Back-and-forth strokes between `start` and `start + stroke` (m) at `speed` (m/s), each
/// reversal smoothed over `ramp` seconds (a cosine velocity blend), starting forwards (or
/// backwards when `stroke < 0`).
#[derive(Debug, Clone, Copy)]
pub struct Strokes {
    /// Where the first stroke starts, m.
    pub start: f64,
    /// Signed stroke length, m.
    pub stroke: f64,
    /// Speed, m/s.
    pub speed: f64,
    /// Duration of a reversal, s.
    pub ramp: f64,
}

impl Strokes {
    /// Duration of one stroke (one way), s.
    pub fn stroke_time(&self) -> f64 {
        self.stroke.abs() / self.speed + self.ramp() / 2.0
    }

    /// The reversal time actually used: `ramp`, but no longer than the stroke takes at speed.
    fn ramp(&self) -> f64 {
        self.ramp.clamp(0.0, self.stroke.abs() / self.speed)
    }

    /// Duration of one slide (forth and back), s.
    pub fn slide_time(&self) -> f64 {
        2.0 * self.stroke_time()
    }
}

impl ArmPath for Strokes {
    fn at(&self, t: f64) -> (f64, f64) {
        // One stroke: ramp up over ramp/2, cruise, ramp down over ramp/2. Displacement of the
        // ramp halves: speed * ramp/4 each, so cruise covers |stroke| - speed*ramp/2.
        let t_stroke = self.stroke_time();
        let dir0 = self.stroke.signum();
        let n = (t / t_stroke).floor().max(0.0);
        let tau = t - n * t_stroke;
        let forward = (n as u64).is_multiple_of(2);
        let dir = if forward { dir0 } else { -dir0 };
        let origin = if forward {
            self.start
        } else {
            self.start + self.stroke
        };
        let half = self.ramp() / 2.0;
        let v = self.speed;
        let len = self.stroke.abs();
        let (s, ds) = if half <= 0.0 {
            ((v * tau).min(len), v)
        } else if tau < half {
            // Velocity v/2 (1 - cos(pi tau / half)).
            let w = std::f64::consts::PI / half;
            (
                v / 2.0 * (tau - (w * tau).sin() / w),
                v / 2.0 * (1.0 - (w * tau).cos()),
            )
        } else if tau < t_stroke - half {
            (v * half / 2.0 + v * (tau - half), v)
        } else {
            let r = t_stroke - tau;
            let w = std::f64::consts::PI / half;
            (
                len - v / 2.0 * (r - (w * r).sin() / w),
                v / 2.0 * (1.0 - (w * r).cos()),
            )
        };
        (origin + dir * s, dir * ds)
    }
}

/// The finger on one line of the surface: the right-hand side of its equations of motion.
#[derive(Debug, Clone)]
pub struct FingerModel {
    env: Envelope,
    m: f64,
    big_m: f64,
    kx: f64,
    kz: f64,
    cx: f64,
    cz: f64,
    kc: f64,
    cc: f64,
    mu: f64,
    v_eps: f64,
    c_arm: f64,
    radius: f64,
    travel: f64,
}

/// Forces and deflections at one state: what the optics read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Readout {
    /// Lateral deflection of the tip relative to the body, m (positive along +x).
    pub lateral: f64,
    /// Normal compression of the finger, m (positive when the tip is pushed up).
    pub normal: f64,
    /// Contact normal force, N.
    pub contact_force: f64,
    /// Moment of the friction force about the tip's centre, N·m (friction acts at the contact
    /// point, the normal force through the centre).
    pub moment: f64,
    /// Tip position along the line, m.
    pub tip_x: f64,
    /// Height of the body's reference point, m.
    pub body_z: f64,
}

impl FingerModel {
    /// The model for `params` on the line whose envelope is `env`.
    pub fn new(params: &FingerParams, env: Envelope) -> Self {
        let m = params.tip_mass_g * 1e-3;
        let big_m = params.body_mass_g * 1e-3;
        let kx = params.lateral_stiffness_n_mm * 1e3;
        let kz = params.normal_stiffness_n_mm * 1e3;
        let kc = params.contact_stiffness_n_m;
        FingerModel {
            env,
            m,
            big_m,
            kx,
            kz,
            cx: 2.0 * params.lateral_damping_ratio * (kx * m).sqrt(),
            cz: 2.0 * params.normal_damping_ratio * (kz * m).sqrt(),
            kc,
            cc: 2.0 * params.contact_damping_ratio * (kc * m).sqrt(),
            mu: params.friction,
            v_eps: params.friction_velocity_mm_s * 1e-3,
            c_arm: params.arm_damping_n_s_m,
            radius: params.tip_radius_mm * 1e-3,
            travel: params.lateral_travel_mm.map_or(f64::INFINITY, |t| t * 1e-3),
        }
    }

    /// Energy stored in the end stop `beyond` metres past the travel (the integral of its
    /// capped force).
    fn end_stop_energy(&self, beyond: f64) -> f64 {
        if beyond <= 0.0 {
            return 0.0;
        }
        let k = END_STOP_FACTOR * self.kx;
        let knee = END_STOP_MAX_FORCE_N / k;
        if beyond <= knee {
            0.5 * k * beyond * beyond
        } else {
            0.5 * k * knee * knee + END_STOP_MAX_FORCE_N * (beyond - knee)
        }
    }

    /// Energy stored in the lateral spring and its end stop at deflection `d` (m), J: what a
    /// tip held back by a crack's wall gives back when it comes free.
    pub fn lateral_energy(&self, d: f64) -> f64 {
        0.5 * self.kx * d * d + self.end_stop_energy(d.abs() - self.travel)
    }

    /// The lateral spring's force on the tip at deflection `d` (m): linear, and
    /// [`END_STOP_FACTOR`] times stiffer beyond the travel.
    #[inline]
    fn lateral_spring(&self, d: f64) -> f64 {
        let beyond = d.abs() - self.travel;
        let stop = if beyond > 0.0 {
            (END_STOP_FACTOR * self.kx * beyond).min(END_STOP_MAX_FORCE_N) * d.signum()
        } else {
            0.0
        };
        -self.kx * d - stop
    }

    /// The envelope the tip rides on.
    pub fn envelope(&self) -> &Envelope {
        &self.env
    }

    /// Static equilibrium on the surface below `x` (m) with the arm still: the start state.
    pub fn rest_state(&self, x: f64) -> State {
        let (e, _) = self.env.at(x);
        let w_body = self.big_m * G;
        let w_total = (self.big_m + self.m) * G;
        let pen = w_total / self.kc;
        let zt = e - pen;
        // Body weight compresses the finger by W/kz.
        let zb = zt - w_body / self.kz;
        [x, zt, 0.0, 0.0, zb, 0.0]
    }

    /// Contact force components acting on the tip `(f_x, f_z)`, the normal force magnitude and
    /// the friction force along the tangent.
    ///
    /// The penalty acts on the vertical penetration `δ = e(x_t) − z_t`: its energy is
    /// `½ k_c δ²`, whose gradient is the force `k_c δ (−e′, 1)`, normal to the envelope. The
    /// damping `c_c δ̇` acts along the same direction, and the total is never attractive.
    #[inline]
    fn contact(&self, y: &State) -> (f64, f64, f64, f64) {
        let (xt, zt, vx, vz) = (y[0], y[1], y[2], y[3]);
        let (e, s) = self.env.at(xt);
        let pen = e - zt;
        if pen <= 0.0 {
            return (0.0, 0.0, 0.0, 0.0);
        }
        let norm = (1.0 + s * s).sqrt();
        let inv = 1.0 / norm;
        // Rate of the vertical penetration.
        let pen_rate = s * vx - vz;
        // Force per unit of the (unnormalised) normal (−s, 1).
        // The damping fades in over the first micrometre of penetration, so the force is
        // continuous at the contact's onset (no jump the Newton iteration cannot follow).
        let fade = (pen / CONTACT_FADE).min(1.0);
        let lambda = (self.kc * pen + self.cc * pen_rate * fade).max(0.0);
        let fn_mag = lambda * norm;
        // Tangent (1, s)/norm.
        let vt = (vx + s * vz) * inv;
        let ft = -self.mu * fn_mag * (vt / self.v_eps).tanh();
        let fx = -s * lambda + ft * inv;
        let fz = lambda + ft * s * inv;
        (fx, fz, fn_mag, ft)
    }

    /// `dy/dt` at time `t`, with the arm on `arm`.
    #[inline]
    pub fn rhs(&self, t: f64, y: &State, arm: &dyn ArmPath) -> State {
        let (xb, vb) = arm.at(t);
        let (xt, zt, vx, vz, zb, vzb) = (y[0], y[1], y[2], y[3], y[4], y[5]);
        let (fcx, fcz, _, _) = self.contact(y);
        // Finger springs: lateral towards the body; the normal compression δz = zt - zb (the
        // tip pushed up towards the body's reference point) pushes the tip down and the body up.
        let fsx = self.lateral_spring(xt - xb) - self.cx * (vx - vb);
        let fsz = self.kz * (zt - zb) + self.cz * (vz - vzb);
        let ax = (fsx + fcx) / self.m;
        let az = (-fsz + fcz) / self.m - G;
        // The body: weight, the finger's reaction, the arm's damping.
        let azb = (fsz - self.big_m * G - self.c_arm * vzb) / self.big_m;
        [vx, vz, ax, az, vzb, azb]
    }

    /// Deflections and contact force at a state, for the optics.
    pub fn readout(&self, t: f64, y: &State, arm: &dyn ArmPath) -> Readout {
        let (xb, _) = arm.at(t);
        let (_, _, fn_mag, ft) = self.contact(y);
        Readout {
            lateral: y[0] - xb,
            normal: y[1] - y[4],
            contact_force: fn_mag,
            moment: ft * self.radius,
            tip_x: y[0],
            body_z: y[4],
        }
    }

    /// Mechanical energy (kinetic + springs + contact penalty + gravity), J. With the arm still
    /// and no input it never grows.
    pub fn energy(&self, y: &State, arm_x: f64) -> f64 {
        let (xt, zt, vx, vz, zb, vzb) = (y[0], y[1], y[2], y[3], y[4], y[5]);
        let (e, _) = self.env.at(xt);
        let pen = (e - zt).max(0.0);
        0.5 * self.m * (vx * vx + vz * vz)
            + 0.5 * self.big_m * vzb * vzb
            + self.lateral_energy(xt - arm_x)
            + 0.5 * self.kz * (zt - zb).powi(2)
            + 0.5 * self.kc * pen * pen
            + G * (self.m * zt + self.big_m * zb)
    }

    /// Surface height at `x` m.
    pub fn surface_at(&self, x: f64) -> f64 {
        self.env.surface_at(x)
    }

    /// Reflectivity at `x` m.
    pub fn reflectivity_at(&self, x: f64) -> f64 {
        self.env.reflectivity_at(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::{Feature, Surface};

    fn flat_model(params: &FingerParams) -> FingerModel {
        let surface = Surface::flat([200.0, 100.0]);
        let profile = surface.profile([0.0, 50.0], [40.0, 50.0], 0.01);
        FingerModel::new(params, Envelope::new(&profile, params.tip_radius_mm))
    }

    #[test]
    fn envelope_of_a_narrow_crack_is_shallow() {
        let crack = |w: f64| Surface {
            size_mm: [200.0, 100.0],
            features: vec![Feature::Crack {
                path: vec![[20.0, 0.0], [20.0, 100.0]],
                width_mm: w,
                depth_mm: 3.0,
                edge_radius_mm: 0.0,
                wall_angle_deg: 90.0,
            }],
        };
        let dip = |w: f64| {
            let p = crack(w).profile([0.0, 50.0], [40.0, 50.0], 0.005);
            let env = Envelope::new(&p, 1.0);
            env.at(0.020).0 * 1e3
        };
        // A 1 mm crack under a 1 mm tip: R - sqrt(R² - (w/2)²) = 0.134 mm.
        assert!((dip(1.0) + 0.134).abs() < 0.01, "{}", dip(1.0));
        // A 5 mm crack lets the tip reach the bottom.
        assert!((dip(5.0) + 3.0).abs() < 1e-9, "{}", dip(5.0));
        assert_eq!(dip(0.0), 0.0);
    }

    #[test]
    fn strokes_go_forth_and_back_smoothly() {
        let s = Strokes {
            start: 0.01,
            stroke: 0.016,
            speed: 0.00389,
            ramp: 0.1,
        };
        let t1 = s.stroke_time();
        let (x_end, v_end) = s.at(t1 - 1e-9);
        assert!((x_end - 0.026).abs() < 1e-6, "{x_end}");
        assert!(v_end.abs() < 1e-6);
        let (x_mid, v_mid) = s.at(t1 / 2.0);
        assert!((x_mid - 0.018).abs() < 1e-4, "{x_mid}");
        assert!((v_mid - 0.00389).abs() < 1e-9);
        let (x_back, v_back) = s.at(1.5 * t1);
        assert!((x_back - 0.018).abs() < 1e-4);
        assert!(v_back < 0.0);
        let (x_home, _) = s.at(2.0 * t1 - 1e-9);
        assert!((x_home - 0.01).abs() < 1e-6);
    }

    #[test]
    fn rest_state_is_an_equilibrium() {
        let p = FingerParams::default();
        let model = flat_model(&p);
        let y = model.rest_state(0.02);
        let f = model.rhs(0.0, &y, &Still(0.02));
        for a in [f[2], f[3], f[5]] {
            assert!(a.abs() < 1e-6, "{f:?}");
        }
    }
}
