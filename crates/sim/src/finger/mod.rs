//! Mechanics of the finger sliding over a surface profile, and the integrators that carry it.
//!
//! ## Model (a vertical plane through the slide line)
//! * The sensor body (mass `M`, the sensor's ~200 g) hangs on the manipulator: it is moved along
//!   the slide at the commanded position `x_b(t)`, and rests on the surface under its own weight,
//!   free to move vertically against the arm's viscous damping.
//! * The tip, a sphere of radius `R` and gram-scale mass `m`, is joined to the body by the
//!   compliant middle part of the finger: lateral and normal linear spring–dampers. The lateral
//!   deflection `δx = x_t − x_b` and the normal compression `δz = z_t − z_b` are what the
//!   deformation fibres D1–D3 see.
//! * Contact: the sphere meets the surface along its *rolling envelope* `e(x)` (the height of the
//!   sphere's lowest point when it rests on the profile above `x`), so a crack narrower than the
//!   tip barely dips it and the tip rolls round edges. The penetration `δ = e(x_t) − z_t` gives a
//!   penalty force `k_c δ_n + c_c δ̇_n` (`k_c ≥ 1e5 N/m`) along the envelope's normal: its
//!   horizontal part is what catches the tip on a crack's far edge. Coulomb friction opposes
//!   sliding along the tangent, regularised as `μ F_n tanh(v/v_ε)`.
//!
//! The state is `[x_t, z_t, ẋ_t, ż_t, z_b, ż_b]` in metres and m/s. The contact mode
//! (`k_c/m ≈ 1e8 s⁻²`, about 1.6 kHz) is far above the 400 Hz output rate: an explicit step of
//! 2.5 ms is unstable, so the default integrator is the L-stable two-stage SDIRK, which damps the
//! contact ringing that no sensor resolves and follows the slow motion at second order
//! (see the work-precision report, `crackbot sim work-precision`).
//!
//! The parts: `model` (the parameters, the envelope, the arm's path and the equations of
//! motion) and `integrator` (the time-stepping methods and the [`Stepper`] that runs them).

mod integrator;
mod model;

pub use integrator::{Integrator, Stepper, Work};
pub use model::{
    ArmPath, Envelope, FingerModel, FingerParams, Readout, State, Still, Strokes, MAX_SLOPE, STATE,
};
