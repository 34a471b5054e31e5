//! Running the finger along a line of a surface: mechanics + optics, one 400 Hz sample at a time.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::finger::{
    ArmPath, Envelope, FingerModel, FingerParams, Integrator, State, Stepper, Strokes,
};
use crate::optics::{proximity_intensity, Electronics, OpticsParams, Scene1d, CHANNELS};
use crate::surface::{Point, Profile, Surface};
use crate::{list, SensorParams, SimError};

/// The sensor's sampling rate, Hz: the wire protocol's `crackbot_protocol::SAMPLE_RATE_HZ`.
pub const SAMPLE_RATE_HZ: f64 = crackbot_protocol::SAMPLE_RATE_HZ as f64;

/// Extra length of the tabulated profile before and after the stroke, mm (room for the
/// proximity fibre's look-ahead and the tip's radius).
const MARGIN_MM: f64 = 8.0;

/// Longest stroke simulated, mm (the profile is tabulated every few µm).
pub const MAX_STROKE_MM: f64 = 2000.0;

/// One slide line: where the strokes run on the plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideLine {
    /// Where the first stroke starts, mm on the plate.
    pub start: Point,
    /// Direction of the first stroke (normalised internally).
    pub direction: Point,
    /// Stroke length, mm.
    pub stroke_mm: f64,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f64,
}

/// One output sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time since the start, s.
    pub t: f64,
    /// Arm (commanded) position along the line, mm from the first stroke's start.
    pub arm_mm: f64,
    /// Arm velocity along the line, mm/s.
    pub arm_velocity_mm_s: f64,
    /// Lateral deflection of the tip, mm.
    pub lateral_mm: f64,
    /// Normal compression of the finger, mm.
    pub normal_mm: f64,
    /// Contact force, N.
    pub contact_force_n: f64,
    /// Friction moment about the tip's centre, N·mm.
    pub moment_nmm: f64,
    /// Tip position along the line, mm from the first stroke's start.
    pub tip_x_mm: f64,
    /// Height of the tip's lowest point, mm.
    pub tip_z_mm: f64,
    /// Distance seen by the proximity fibre, mm.
    pub proximity_mm: f64,
    /// Channel values before the ADC (D1, D2, D3, P), counts.
    pub analog: [f64; CHANNELS],
    /// ADC codes (D1, D2, D3, P).
    pub counts: [f64; CHANNELS],
}

/// The finger sliding back and forth along one line of a surface.
#[derive(Debug, Clone)]
pub struct SlideSim {
    model: FingerModel,
    electronics: Electronics,
    stepper: Stepper,
    arm: Strokes,
    state: State,
    t: f64,
    /// Offset of the stroke start in the tabulated profile, m.
    origin: f64,
    proximity: ProximityGeometry,
    plate_reflectivity: f64,
    profile: Profile,
    finger: FingerParams,
    /// The arm's last position when a real arm's pose drives it, m.
    followed: Option<f64>,
}

/// An arm position given sample by sample: from the last one to the new one at a steady speed
/// over one sample.
#[derive(Debug, Clone, Copy)]
struct Followed {
    t0: f64,
    x0: f64,
    x1: f64,
    dt: f64,
}

impl ArmPath for Followed {
    fn at(&self, t: f64) -> (f64, f64) {
        let u = ((t - self.t0) / self.dt).clamp(0.0, 1.0);
        (
            self.x0 + u * (self.x1 - self.x0),
            (self.x1 - self.x0) / self.dt,
        )
    }
}

/// Points across the proximity fibre's spot (the midpoint rule over its diameter).
///
/// A mark narrower than the spot darkens the fibre by the share of these points it covers, so
/// the view steps as the spot moves over it, and the deepest step may hold only over a sliver
/// of travel. With 5 points (0.23 mm apart for the fitted 1.128 mm spot, the default until
/// 2026-11-29) a 0.5 mm print covered three points over 0.05 mm of travel and two elsewhere,
/// and a 0.7 mm one read 0.38 or 0.51 of its share by where the samples fell: a slow pass in
/// contact (0.01 mm between samples) caught the deeper step and a fast raised one (0.1 mm)
/// mostly missed it, so a thin print lost share raised, as only a crack should, and read as one
/// (`crackbot_tactile::print_check`). With 101 points (0.011 mm apart) a print of 0.45–0.7 mm
/// keeps its share within 4 % at any height and sampling (`tests/extreme.rs`,
/// `a_thin_print_darkens_the_fibre_alike_at_every_height_and_sampling`; 25 points still stepped
/// by 8 %). On the simulated trial scenes 12780–12899 (real time) the print ratios of printed
/// lines of 0.5–0.7 mm went from 0.87 / 0.95 at their 5th percentile / median to 0.90 / 0.97,
/// cracks' did not move (`crates/research/EXPERIMENTS.md`, "The simulated fibre's spot without
/// steps"). Cost: the finger's stepping takes 2.2 times as long (`benches/sim.rs`,
/// `sim_finger_slide/sdirk2_x1_default`, one core: 3.19 → 6.93 ms per 8.3 s slide, still about
/// 1 200 times real time); missions, paced by the arm's real time, did not change.
pub const SPOT_POINTS: usize = 101;

/// Where the proximity fibre sits and how it sees, SI units (the calibration varies these).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProximityGeometry {
    /// Height of the fibre's end above the tip's lowest point, m.
    pub height: f64,
    /// Look-ahead along the line, m.
    pub offset: f64,
    /// Diameter of the spot, m.
    pub spot: f64,
    /// Distance of the intensity curve's peak, mm.
    pub peak_mm: f64,
    /// Half-angle of the fibre's cone, radians: 0 looks straight down from every point of the
    /// spot; above 0 the spot's rays fan out and are traced to the first surface they meet
    /// (walls shade a crack's floor, and a surface seen at a grazing angle returns less light).
    pub cone: f64,
}

impl ProximityGeometry {
    /// The geometry described by `optics` (mm there, SI here).
    pub fn of(optics: &OpticsParams) -> Self {
        ProximityGeometry {
            height: optics.proximity_height_mm * 1e-3,
            offset: optics.proximity_offset_mm * 1e-3,
            spot: optics.proximity_spot_mm.max(0.0) * 1e-3,
            peak_mm: optics.proximity_peak_mm,
            cone: optics.proximity_cone_deg.to_radians(),
        }
    }

    /// The proximity view with the tip at `(tip_x, tip_z)` (m) on `model`'s line.
    ///
    /// Points across the spot each look at the surface and return the distance curve at the
    /// length of their look, times the reflectivity where it lands, times the cosine between
    /// the look and the surface's normal there; the view is their mean. With no cone,
    /// [`SPOT_POINTS`] points look straight down (cosine 1). With a cone, [`CONE_RAYS`] rays,
    /// tilted across it, are traced to the first surface they meet ([`trace_ray`]; a matt
    /// surface), and a ray that meets none within [`MAX_RAY`] returns nothing.
    pub fn view(
        &self,
        model: &FingerModel,
        tip_x: f64,
        tip_z: f64,
        plate_reflectivity: f64,
    ) -> Scene1d {
        let fibre_x = tip_x + self.offset;
        let fibre_z = tip_z + self.height;
        let traced = self.cone > 0.0;
        let n = if traced { CONE_RAYS } else { SPOT_POINTS };
        let mut intensity = 0.0;
        let mut distance = 0.0;
        for k in 0..n {
            let u = (k as f64 + 0.5) / n as f64 - 0.5;
            let x0 = fibre_x + u * self.spot;
            let look = if traced {
                trace_ray(model, x0, fibre_z, 2.0 * u * self.cone)
            } else {
                Some((x0, fibre_z - model.surface_at(x0), 1.0))
            };
            match look {
                Some((x, length, cosine)) => {
                    let d_mm = length * 1e3;
                    distance += d_mm;
                    intensity +=
                        proximity_intensity(d_mm, self.peak_mm) * model.reflectivity_at(x) * cosine;
                }
                None => distance += MAX_RAY * 1e3,
            }
        }
        Scene1d {
            proximity_distance_mm: distance / n as f64,
            intensity: plate_reflectivity * intensity / n as f64,
        }
    }
}

/// What the proximity fibre of a finger held off the surface sees: the tip's lowest point
/// `tip_height_mm` above the plate's plane at `tip` (plate frame, mm), the fibre looking
/// `offset` ahead along `dir` (a unit vector; the way the arm moves). The spot's
/// [`SPOT_POINTS`] points look straight down at the [`Surface`]'s height and reflectivity there
/// (a cone is not traced off the slide line: the fibre is far enough above a crack's walls that
/// they shade little). A point at or below the surface sees nothing (the curve is 0 at contact).
///
/// This is what the arm's hover passes measure: ink darkens the fibre by the same share at
/// every height, while a crack's floor, farther away, darkens it by less the higher the
/// fibre is (`crackbot_tactile::print_check`).
pub fn hover_view(
    optics: &OpticsParams,
    surface: &Surface,
    plate_reflectivity: f64,
    tip: Point,
    dir: [f64; 2],
    tip_height_mm: f64,
) -> Scene1d {
    let fibre = [
        tip[0] + optics.proximity_offset_mm * dir[0],
        tip[1] + optics.proximity_offset_mm * dir[1],
    ];
    let fibre_z = tip_height_mm + optics.proximity_height_mm;
    let spot = optics.proximity_spot_mm.max(0.0);
    let (mut intensity, mut distance) = (0.0, 0.0);
    for k in 0..SPOT_POINTS {
        let u = (k as f64 + 0.5) / SPOT_POINTS as f64 - 0.5;
        let p = [fibre[0] + u * spot * dir[0], fibre[1] + u * spot * dir[1]];
        let d = fibre_z - surface.height_mm(p);
        distance += d;
        intensity += proximity_intensity(d, optics.proximity_peak_mm) * surface.reflectivity(p);
    }
    Scene1d {
        proximity_distance_mm: distance / SPOT_POINTS as f64,
        intensity: plate_reflectivity * intensity / SPOT_POINTS as f64,
    }
}

/// Rays across the proximity fibre's cone.
pub const CONE_RAYS: usize = 9;

/// Longest proximity ray traced, m (the curve is below 1 % of its peak well before).
pub const MAX_RAY: f64 = 0.012;

/// The first point where the ray from `(x0, z0)`, tilted `angle` from straight down (towards
/// +x for a positive angle), meets `model`'s surface: `(x, length, cosine)`, with the cosine
/// between the reversed ray and the surface's normal there (0 for a surface seen edge-on).
/// A start at or below the surface meets it at once.
fn trace_ray(model: &FingerModel, x0: f64, z0: f64, angle: f64) -> Option<(f64, f64, f64)> {
    const MIN_STEP: f64 = 5e-6;
    const MAX_STEP: f64 = 5e-4;
    let (sin, cos) = angle.sin_cos();
    let gap_at = |s: f64| {
        let x = x0 + s * sin;
        (x, z0 - s * cos - model.surface_at(x))
    };
    let (_, mut gap) = gap_at(0.0);
    if gap <= 0.0 {
        return Some((x0, 0.0, 1.0));
    }
    let mut s = 0.0;
    while s < MAX_RAY {
        let step = (0.5 * gap).clamp(MIN_STEP, MAX_STEP);
        let (_, next_gap) = gap_at(s + step);
        if next_gap <= 0.0 {
            let hit = s + step * gap / (gap - next_gap);
            let (x, _) = gap_at(hit);
            let h = 2e-5;
            let slope = (model.surface_at(x + h) - model.surface_at(x - h)) / (2.0 * h);
            // Normal (-slope, 1); reversed ray (-sin, cos).
            let cosine = ((slope * sin + cos) / (1.0 + slope * slope).sqrt()).max(0.0);
            return Some((x, hit, cosine));
        }
        s += step;
        gap = next_gap;
    }
    None
}

impl SlideSim {
    /// A simulation of `sensor` sliding along `line` on `surface` (plate reflectivity
    /// `plate_reflectivity`), integrated with `integrator`, noise and per-recording changes
    /// drawn from `seed`.
    pub fn new(
        surface: &Surface,
        plate_reflectivity: f64,
        line: &SlideLine,
        sensor: &SensorParams,
        integrator: Integrator,
        seed: u64,
    ) -> Result<Self, SimError> {
        sensor.finger.validate()?;
        sensor.optics.validate()?;
        integrator.validate()?;
        if !line.start.iter().all(|v| v.is_finite()) {
            return Err(SimError::setting(
                "slide.start",
                list(&line.start),
                "finite (mm)",
            ));
        }
        if !(plate_reflectivity.is_finite() && plate_reflectivity >= 0.0) {
            return Err(SimError::setting(
                "plate_reflectivity",
                plate_reflectivity,
                "≥ 0",
            ));
        }
        let norm = (line.direction[0].powi(2) + line.direction[1].powi(2)).sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(SimError::setting(
                "slide.direction",
                list(&line.direction),
                "a direction of finite, non-zero length",
            ));
        }
        if !(line.stroke_mm.is_finite() && line.stroke_mm > 0.0 && line.stroke_mm <= MAX_STROKE_MM)
        {
            return Err(SimError::setting(
                "slide.stroke_mm",
                line.stroke_mm,
                format!("in (0, {MAX_STROKE_MM}] mm"),
            ));
        }
        if !(line.speed_mm_s.is_finite() && line.speed_mm_s > 0.0) {
            return Err(SimError::setting(
                "slide.speed_mm_s",
                line.speed_mm_s,
                "> 0 mm/s",
            ));
        }
        let dir = [line.direction[0] / norm, line.direction[1] / norm];
        let margin =
            MARGIN_MM + sensor.optics.proximity_offset_mm.abs() + sensor.finger.tip_radius_mm;
        let a = [
            line.start[0] - margin * dir[0],
            line.start[1] - margin * dir[1],
        ];
        let len = line.stroke_mm + 2.0 * margin;
        let b = [a[0] + len * dir[0], a[1] + len * dir[1]];
        let step = (sensor.finger.tip_radius_mm / 100.0).clamp(0.002, 0.02);
        let profile = surface.profile(a, b, step);
        let env = Envelope::new(&profile, sensor.finger.tip_radius_mm);
        let model = FingerModel::new(&sensor.finger, env);
        let origin = margin * 1e-3;
        let arm = Strokes {
            start: origin,
            stroke: line.stroke_mm * 1e-3,
            speed: line.speed_mm_s * 1e-3,
            ramp: 0.05,
        };
        let state = model.rest_state(origin);
        let static_compression_mm = (state[1] - state[4]) * 1e3;
        let electronics = Electronics::new(
            &sensor.optics,
            static_compression_mm,
            ChaCha8Rng::seed_from_u64(seed),
        );
        Ok(SlideSim {
            model,
            electronics,
            stepper: Stepper::new(integrator),
            arm,
            state,
            t: 0.0,
            origin,
            proximity: ProximityGeometry::of(&sensor.optics),
            profile,
            finger: sensor.finger.clone(),
            plate_reflectivity,
            followed: None,
        })
    }

    /// Adds surface roughness along the line: a smooth random height texture of `rms_mm`
    /// (standard deviation) with features about `correlation_mm` long (a sum of 16 cosines
    /// with random wavelengths and phases drawn from `seed`), then rebuilds the envelope and
    /// puts the finger back at rest. Printed plates are not flat to a few µm, and the proximity
    /// fibre sees that.
    pub fn with_roughness(
        mut self,
        rms_mm: f64,
        correlation_mm: f64,
        seed: u64,
    ) -> Result<Self, SimError> {
        if !(rms_mm.is_finite() && rms_mm >= 0.0) {
            return Err(SimError::setting(
                "samples.roughness_rms_mm",
                rms_mm,
                "≥ 0 mm",
            ));
        }
        if !(correlation_mm.is_finite() && correlation_mm > 0.0) {
            return Err(SimError::setting(
                "samples.roughness_correlation_mm",
                correlation_mm,
                "> 0 mm",
            ));
        }
        if rms_mm == 0.0 {
            return Ok(self);
        }
        const WAVES: usize = 16;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let amplitude = rms_mm * (2.0 / WAVES as f64).sqrt();
        let waves: Vec<(f64, f64)> = (0..WAVES)
            .map(|_| {
                // Wavelengths spread around 2π × the correlation length.
                let wavelength = correlation_mm * rng.random_range(2.0..12.0);
                (
                    std::f64::consts::TAU / wavelength,
                    rng.random_range(0.0..std::f64::consts::TAU),
                )
            })
            .collect();
        let step = self.profile.step_mm;
        for (i, h) in self.profile.height.iter_mut().enumerate() {
            let s = i as f64 * step;
            *h += amplitude
                * waves
                    .iter()
                    .map(|(k, phi)| (k * s + phi).cos())
                    .sum::<f64>();
        }
        let env = Envelope::new(&self.profile, self.finger.tip_radius_mm);
        self.model = FingerModel::new(&self.finger, env);
        self.state = self.model.rest_state(self.origin);
        Ok(self)
    }

    /// Duration of one slide (a stroke forth and back), s.
    pub fn slide_time(&self) -> f64 {
        self.arm.slide_time()
    }

    /// The mechanical state (SI units).
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The finger model.
    pub fn model(&self) -> &FingerModel {
        &self.model
    }

    /// The stepper's work counters.
    pub fn work(&self) -> crate::finger::Work {
        self.stepper.work
    }

    /// What the proximity fibre sees now.
    pub fn proximity_view(&self) -> Scene1d {
        self.proximity.view(
            &self.model,
            self.state[0],
            self.state[1],
            self.plate_reflectivity,
        )
    }

    /// Where the stroke starts in the model's line coordinate, m.
    pub fn origin(&self) -> f64 {
        self.origin
    }

    /// Advances one output sample (1/400 s) and returns it.
    pub fn next_sample(&mut self) -> Result<Sample, SimError> {
        let arm = self.arm;
        self.sample_with(&arm)
    }

    /// Advances one output sample with the arm where a real arm says it is: `arm_mm` along the
    /// line from the stroke's start (a pose the arm reported, projected on the line), reached
    /// at a steady speed from the last one. A position beyond the stroke's ends by more than
    /// the tabulated margin is held at its edge.
    pub fn next_sample_following(&mut self, arm_mm: f64) -> Result<Sample, SimError> {
        if !arm_mm.is_finite() {
            return Err(SimError::setting("arm_mm", arm_mm, "finite (mm)"));
        }
        let dt = 1.0 / SAMPLE_RATE_HZ;
        let edge = self.origin * 0.9;
        let x1 = (self.origin + arm_mm * 1e-3).clamp(
            self.origin - edge,
            self.origin + self.arm.stroke.abs() + edge,
        );
        let x0 = self.followed.unwrap_or(x1);
        self.followed = Some(x1);
        let arm = Followed {
            t0: self.t,
            x0,
            x1,
            dt,
        };
        self.sample_with(&arm)
    }

    fn sample_with(&mut self, arm: &dyn ArmPath) -> Result<Sample, SimError> {
        let dt = 1.0 / SAMPLE_RATE_HZ;
        self.stepper
            .advance(&self.model, arm, self.t, dt, &mut self.state)?;
        self.t += dt;
        if !self.state.iter().all(|v| v.is_finite()) {
            return Err(SimError::Integration {
                t: self.t,
                reason: "the state is not finite".into(),
            });
        }
        let readout = self.model.readout(self.t, &self.state, arm);
        let view = self.proximity_view();
        let d_mm = view.proximity_distance_mm;
        let analog = self.electronics.analog(&readout, &view, dt);
        let counts = self.electronics.quantise(&analog);
        let (xb, vb) = arm.at(self.t);
        Ok(Sample {
            t: self.t,
            arm_mm: (xb - self.origin) * 1e3,
            arm_velocity_mm_s: vb * 1e3,
            lateral_mm: readout.lateral * 1e3,
            normal_mm: readout.normal * 1e3,
            contact_force_n: readout.contact_force,
            moment_nmm: readout.moment * 1e3,
            tip_x_mm: (self.state[0] - self.origin) * 1e3,
            tip_z_mm: self.state[1] * 1e3,
            proximity_mm: d_mm,
            analog,
            counts,
        })
    }
}
