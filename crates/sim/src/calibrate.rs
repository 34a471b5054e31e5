//! Calibration of the simulated sensor against the authors' real recordings.
//!
//! Fitted on **repetition 1 only** (of `tactile/type` and `tactile/width`); repetitions 2 and 3
//! are left for measuring the transfer. What is fitted:
//!
//! * **Mechanics and plates** ([`MECHANICS`]): the tip's radius, the finger's lateral stiffness
//!   (with the haptic device's servo in series: the real position column jumps where the finger
//!   sticks), the tip–PLA friction, the cracks' depth and wall angle, the bump's radius and
//!   height. Nelder–Mead in log space; each candidate simulates both experiments
//!   ([`CALIBRATION_SLIDES`] slides per plate, noise-free) and gets its optics refitted.
//! * **Optics**: the proximity channel (dark level, peak, peak distance, fibre height,
//!   look-ahead, spot) jointly, then each deformation channel's gains for lateral deflection,
//!   normal compression and friction moment, by Nelder–Mead.
//!
//! The objective needs no alignment between real and simulated slides (the real feature
//! positions are unknown): for every plate and sliding direction, the quantiles (5 %, 15 %, …,
//! 95 %) of each channel, the deformation channels relative to their recording's median (their
//! levels move with the fibre cables between plates and sessions; the plate mounts,
//! [`fit_mounts`], take those), the proximity channel as it is. The search minimises
//! [`weighted_loss`] (D1 and D2, which the classifiers read, weighted most). Noise levels come
//! from the first differences of the real flat recordings, roughness from the flat plate's
//! proximity spread ([`fit_roughness`]).
//!
//! Fit (`crackbot sim calibrate --real ../shared/data/tactile/type --real-width
//! ../shared/data/tactile/width --repetition 1 --evaluations 240 --mechanics-evaluations 60`,
//! about 3 minutes on one core), quantile distance in RMS counts:
//!
//! | | D1 | D2 | D3 | P |
//! |---|---|---|---|---|
//! | simulator before this fit (10 mm tip, 1 N/mm, μ 0.15, bump r 6 h 1, crack 8 mm deep) | 64.0 | 26.5 | 78.8 | 99.6 |
//! | fitted ([`calibrated_sensor`], [`calibrated_samples`]) | 4.35 | 2.51 | 5.22 | 43.3 |
//!
//! Fitted: tip radius 4.4 mm, lateral stiffness 0.59 N/mm, friction 0.33, cracks 2.5 mm deep
//! with 73° walls, bump of 3.9 mm base radius and 2.4 mm height. Since then, by the transfer
//! measures (see [`calibrated_samples`]): vertical walls, the wavy plate's wave 1.25 mm, the
//! width plates' cracks 2.8 mm deep, and the bump 8 mm in radius and 1.5 mm high (the fitted cap
//! was a wall the simulated tip jumped, and every real-trained model read it as a crack). The
//! deformation channels' excursions over a crack are the real ones' size.
//!
//! Transfer, measured on repetitions 2 and 3 only: see the crate's `docs/calibration.md`.
//!
//! Optional ([`SearchSettings`]): the tip-speed quantiles of the authors' position column as a
//! further target ([`speed_loss`]; the committed fit's tip jams in wide cracks where the real
//! one never stops), the proximity dark level measured instead of fitted
//! ([`real_dark_counts`]), the fibre kept beyond its curve's peak, some mechanics held fixed.

use crackbot_recording::Recording;
use serde::Serialize;

use crate::experiment::ExperimentConfig;
use crate::finger::{FingerModel, FingerParams, Integrator};
use crate::optics::OpticsParams;
pub use crate::plates::{calibrated_mounts, calibrated_samples, calibrated_sensor};
use crate::plates::{Experiment, PlateMount, Samples};
use crate::run::{ProximityGeometry, Sample, SlideLine, SlideSim, SAMPLE_RATE_HZ};
use crate::{SensorParams, SimError};

/// Quantile levels compared between real and simulated channels.
pub const QUANTILES: [f64; 10] = [0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75, 0.85, 0.95];

/// Fits each plate's mount of `config`'s experiment to the `real` recordings (any number per
/// plate, recognised by their label): the deformation channels' median offsets and the
/// proximity channel's reflectivity ratio between real and simulated recordings.
pub fn fit_mounts(
    config: &ExperimentConfig,
    real: &[Recording],
) -> Result<Vec<PlateMount>, SimError> {
    let mut neutral = config.clone();
    neutral.mounts.clear();
    let traces = simulate_traces(&neutral)?;
    let dark = config.sensor.optics.proximity_dark_counts;
    let median = |v: Vec<f64>| sorted_finite(v).map(|v| v[v.len() / 2]);
    let mut mounts = Vec::with_capacity(traces.len());
    for trace in &traces {
        let rows: Vec<[f64; 4]> = real
            .iter()
            .flat_map(|r| r.rows.iter())
            .filter(|row| row.label == trace.label)
            .map(crackbot_recording::Row::channels)
            .collect();
        if rows.is_empty() {
            return Err(SimError::NoRealRecordingOfPlate { label: trace.label });
        }
        let mut m = PlateMount::default();
        let real_med = |c: usize| median(rows.iter().map(|r| r[c]).collect());
        let sim_med = |c: usize| median(trace.samples.iter().map(|s| s.analog[c]).collect());
        for c in 0..3 {
            if let (Some(a), Some(b)) = (real_med(c), sim_med(c)) {
                m.offset_counts[c] = a - b;
            }
        }
        // Reflectivity: the ratio above dark of the medians of P's upper three quarters (the
        // flat stretches of a crack plate, without its dips; the same rule for real and
        // simulated recordings of every plate).
        let upper_median = |v: Vec<f64>| {
            sorted_finite(v).map(|v| {
                let upper = &v[v.len() / 4..];
                upper[upper.len() / 2]
            })
        };
        let level_real = upper_median(rows.iter().map(|r| r[3]).collect());
        let level_sim = upper_median(trace.samples.iter().map(|s| s.analog[3]).collect());
        if let (Some(a), Some(b)) = (level_real, level_sim) {
            if (b - dark).abs() > 1.0 {
                m.reflectivity = ((a - dark) / (b - dark)).max(0.0);
            }
        }
        mounts.push(m);
    }
    Ok(mounts)
}

/// Quantiles of one channel for one class and direction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelQuantiles {
    /// Class label.
    pub label: f64,
    /// Sliding direction (0 towards +x, 1 back: the recordings' column 6).
    pub direction: u8,
    /// Channel index (0 D1, 1 D2, 2 D3, 3 P).
    pub channel: usize,
    /// The quantiles at [`QUANTILES`].
    pub values: Vec<f64>,
}

/// The finite values of `v`, sorted; `None` when there are none.
fn sorted_finite(mut v: Vec<f64>) -> Option<Vec<f64>> {
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then_some(v)
}

fn quantiles(v: Vec<f64>) -> Vec<f64> {
    quantiles_at(v, &QUANTILES)
}

/// The quantiles of `v` at `levels` (zeros without finite values).
fn quantiles_at(v: Vec<f64>, levels: &[f64]) -> Vec<f64> {
    match sorted_finite(v) {
        Some(v) => levels
            .iter()
            .map(|q| v[((v.len() - 1) as f64 * q).round() as usize])
            .collect(),
        None => vec![0.0; levels.len()],
    }
}

/// Low tail quantiles of the proximity channel that [`ProximityRules::tails`] adds to
/// [`QUANTILES`]: the short dips into the dark over a crack, which the 5 % quantile misses
/// (a 1 mm crack is dark for about 1 % of a recording).
pub const P_TAILS: [f64; 3] = [0.005, 0.01, 0.02];

/// [`QUANTILES`] followed by [`P_TAILS`].
fn levels_with_tails() -> Vec<f64> {
    QUANTILES.iter().chain(&P_TAILS).copied().collect()
}

/// The median of each channel of one recording (`None` when it has no rows).
fn recording_medians(r: &Recording) -> Option<[f64; 4]> {
    let mut out = [0.0; 4];
    for (c, o) in out.iter_mut().enumerate() {
        let v = sorted_finite(r.rows.iter().map(|row| row.channels()[c]).collect())?;
        *o = v[v.len() / 2];
    }
    Some(out)
}

/// The real targets: channel quantiles per class and direction, from `recordings` (each with
/// its label in the rows). The deformation channels (D1, D2, D3) are taken relative to their
/// recording's median: their levels shift between plates and sessions with the fibre cables
/// (that is the plate mounts' business, [`fit_mounts`]), their excursions are the finger's.
/// The proximity channel is taken as it is.
pub fn real_quantiles(recordings: &[Recording]) -> Vec<ChannelQuantiles> {
    real_quantiles_with(recordings, false)
}

/// [`real_quantiles`], the proximity channel's with [`P_TAILS`] appended when `p_tails`
/// ([`channel_loss`] then compares those too).
pub fn real_quantiles_with(recordings: &[Recording], p_tails: bool) -> Vec<ChannelQuantiles> {
    let tails = levels_with_tails();
    let mut labels: Vec<f64> = recordings
        .iter()
        .filter_map(crackbot_recording::Recording::label)
        .collect();
    labels.sort_by(f64::total_cmp);
    labels.dedup();
    let medians: Vec<[f64; 4]> = recordings
        .iter()
        .map(|r| recording_medians(r).unwrap_or_default())
        .collect();
    let mut out = Vec::new();
    for &label in &labels {
        for direction in [0u8, 1] {
            for channel in 0..4 {
                let values = recordings
                    .iter()
                    .zip(&medians)
                    .flat_map(|(r, m)| {
                        let shift = if channel < 3 { m[channel] } else { 0.0 };
                        r.rows
                            .iter()
                            .filter(move |row| row.label == label && row.direction == direction)
                            .map(move |row| row.channels()[channel] - shift)
                    })
                    .collect();
                let values = if p_tails && channel == 3 {
                    quantiles_at(values, &tails)
                } else {
                    quantiles(values)
                };
                out.push(ChannelQuantiles {
                    label,
                    direction,
                    channel,
                    values,
                });
            }
        }
    }
    out
}

/// Samples between the two ends of a tip-speed measurement (0.1 s at 400 Hz).
pub const SPEED_SPAN: usize = 40;

/// The position column's speeds, mm/s: over [`SPEED_SPAN`] samples, every 10 samples, of a
/// sequence of positions (mm); non-finite ones left out.
fn speeds(x_mm: &[f64]) -> impl Iterator<Item = f64> + '_ {
    let dt = SPEED_SPAN as f64 / SAMPLE_RATE_HZ;
    (0..x_mm.len().saturating_sub(SPEED_SPAN))
        .step_by(10)
        .map(move |i| (x_mm[i + SPEED_SPAN] - x_mm[i]).abs() / dt)
        .filter(|v| v.is_finite())
}

/// Quantiles ([`QUANTILES`]) of the speeds ([`speeds`]) of a sequence of positions (mm);
/// `None` when it is too short.
pub fn speed_quantiles(x_mm: &[f64]) -> Option<Vec<f64>> {
    let v: Vec<f64> = speeds(x_mm).collect();
    (!v.is_empty()).then(|| quantiles(v))
}

/// The real tip-speed targets: per class label, the quantiles of the position column's speed
/// ([`speed_quantiles`]) over all its recordings. The authors' encoder shows the finger crossing
/// every plate, the widest cracks included, at the arm's pace, stopping only where the stroke
/// turns (about 1.5 % of the time): a simulated finger that jams in a crack misses this target.
pub fn real_speed_quantiles(recordings: &[Recording]) -> Vec<(f64, Vec<f64>)> {
    let mut labels: Vec<f64> = recordings
        .iter()
        .filter_map(crackbot_recording::Recording::label)
        .collect();
    labels.sort_by(f64::total_cmp);
    labels.dedup();
    labels
        .into_iter()
        .filter_map(|label| {
            let mut all = Vec::new();
            for r in recordings.iter().filter(|r| r.label() == Some(label)) {
                let x: Vec<f64> = r.rows.iter().map(|row| row.x_mm).collect();
                all.extend(speeds(&x));
            }
            (!all.is_empty()).then(|| (label, quantiles(all)))
        })
        .collect()
}

/// Mean squared quantile distance (mm/s)² between the simulated tips' speeds and the real
/// targets, over the labels both have.
pub fn speed_loss(traces: &[Trace], targets: &[(f64, Vec<f64>)]) -> f64 {
    let mut d = SquaredDistance::default();
    for (label, target) in targets {
        let Some(trace) = traces.iter().find(|t| t.label == *label) else {
            continue;
        };
        let x: Vec<f64> = trace.samples.iter().map(|s| s.tip_x_mm).collect();
        let Some(q) = speed_quantiles(&x) else {
            continue;
        };
        d.add(&q, target);
    }
    d.mean()
}

/// Running mean of squared differences between paired quantiles.
#[derive(Default)]
struct SquaredDistance {
    total: f64,
    n: usize,
}

impl SquaredDistance {
    fn add(&mut self, a: &[f64], b: &[f64]) {
        for (x, y) in a.iter().zip(b) {
            self.total += (x - y).powi(2);
            self.n += 1;
        }
    }

    /// The mean, 0 when nothing was added.
    fn mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.total / self.n as f64
        }
    }
}

/// How hard [`calibrate`] searches, and what it leaves alone.
#[derive(Debug, Clone, PartialEq)]
pub struct SearchSettings {
    /// Evaluations per Nelder–Mead run of the optics.
    pub evaluations: usize,
    /// Mechanics candidates simulated, each with its optics refitted.
    pub mechanics_evaluations: usize,
    /// Weight of the tip-speed term ([`speed_loss`]) against [`weighted_loss`].
    pub speed_weight: f64,
    /// Names of [`MECHANICS`] kept at the starting configuration's values.
    pub fixed: Vec<String>,
    /// Constraints on the proximity fit.
    pub proximity: ProximityRules,
}

impl Default for SearchSettings {
    fn default() -> Self {
        SearchSettings {
            evaluations: 300,
            mechanics_evaluations: 60,
            speed_weight: 0.0,
            fixed: Vec::new(),
            proximity: ProximityRules::default(),
        }
    }
}

impl SearchSettings {
    /// Which of [`MECHANICS`] are searched; an unknown name in `fixed` is an error naming it.
    pub fn free_mask(&self) -> Result<[bool; 7], SimError> {
        let mut free = [true; 7];
        for name in &self.fixed {
            let k = MECHANICS.iter().position(|m| m == name).ok_or_else(|| {
                SimError::setting(
                    "fixed",
                    format!("{name:?}"),
                    format!("a mechanics parameter, one of {}", MECHANICS.join(", ")),
                )
            })?;
            free[k] = false;
        }
        let spot = self.proximity.min_spot_mm;
        if !(spot.is_finite() && spot >= 0.0) {
            return Err(SimError::setting("proximity.min_spot_mm", spot, "≥ 0 mm"));
        }
        if !(self.speed_weight.is_finite() && self.speed_weight >= 0.0) {
            return Err(SimError::setting("speed_weight", self.speed_weight, "≥ 0"));
        }
        Ok(free)
    }
}

/// A weight of the tip-speed term ([`speed_loss`], (mm/s)²) in the mechanics search that
/// makes it count, against [`weighted_loss`] (counts²): 1 mm/s RMS off costs as much as 31.6
/// counts RMS of P. The committed calibration was fitted without it (weight 0, the default of
/// [`SearchSettings`]); see the crate's `docs/calibration.md` for what the term does.
pub const SPEED_WEIGHT: f64 = 1000.0;

/// Quantile of the real proximity readings taken as the fibre's dark level.
pub const DARK_QUANTILE: f64 = 0.005;

/// The proximity fibre's dark level (nothing in view), counts: the [`DARK_QUANTILE`] quantile
/// of every real proximity reading, reached where the fibre looks into a crack. `None` without
/// finite readings.
pub fn real_dark_counts(recordings: &[&Recording]) -> Option<f64> {
    let v = sorted_finite(
        recordings
            .iter()
            .flat_map(|r| r.rows.iter().map(|row| row.channels()[3]))
            .collect(),
    )?;
    let i = ((v.len() - 1) as f64 * DARK_QUANTILE).round() as usize;
    Some(v[i])
}

/// One simulated recording's mechanics, kept for refitting the optics.
#[derive(Debug, Clone)]
pub struct Trace {
    /// Class label.
    pub label: f64,
    /// The samples (mechanics; their optics are ignored).
    pub samples: Vec<Sample>,
    /// The model, for surface lookups.
    pub model: FingerModel,
    /// Stroke origin in the model's line coordinate, m.
    pub origin: f64,
}

/// The sensor without its random parts (white noise, drift, per-recording offset and gain):
/// what calibration compares with the real signals' levels.
pub fn noise_free(sensor: &SensorParams) -> SensorParams {
    let mut s = sensor.clone();
    s.optics.noise_counts = [0.0; 4];
    s.optics.drift_counts_per_sqrt_s = 0.0;
    s.optics.recording_offset_sigma_counts = 0.0;
    s.optics.recording_gain_sigma = 0.0;
    s
}

/// Simulates one recording per surface of `config` (`config.slides` slides, noise-free
/// electronics, the stroke starting 7.5 mm before the feature) for calibration.
pub fn simulate_traces(config: &ExperimentConfig) -> Result<Vec<Trace>, SimError> {
    let sensor = noise_free(&config.sensor);
    let mut traces = Vec::new();
    for (k, (_, label, surface, edge_x)) in config.surfaces().into_iter().enumerate() {
        let line = SlideLine {
            start: [edge_x - 7.5, 50.0],
            direction: [1.0, 0.0],
            stroke_mm: config.stroke_mm,
            speed_mm_s: config.speed_mm_s,
        };
        let mut sim = SlideSim::new(
            &surface,
            1.0,
            &line,
            &sensor,
            config.integrator,
            config.seed + k as u64,
        )?;
        let n = (config.slides as f64 * sim.slide_time() * SAMPLE_RATE_HZ).round() as usize;
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n {
            samples.push(sim.next_sample()?);
        }
        traces.push(Trace {
            label,
            samples,
            model: sim.model().clone(),
            origin: sim.origin(),
        });
    }
    Ok(traces)
}

/// The recordings' direction column of a sample: 0 moving towards +x, 1 back (the authors'
/// convention).
fn direction_of(s: &Sample) -> u8 {
    u8::from(s.arm_velocity_mm_s < 0.0)
}

/// The noise-free value of channel `channel` for a sample under `optics`.
fn channel_value(
    optics: &OpticsParams,
    static_mm: f64,
    trace: &Trace,
    s: &Sample,
    channel: usize,
) -> f64 {
    if channel < 3 {
        optics.rest_counts[channel]
            + optics.lateral_gain[channel] * s.lateral_mm
            + optics.normal_gain[channel] * (s.normal_mm - static_mm)
            + optics.moment_gain[channel] * s.moment_nmm
    } else {
        let view = ProximityGeometry::of(optics).view(
            &trace.model,
            trace.origin + s.tip_x_mm * 1e-3,
            s.tip_z_mm * 1e-3,
            1.0,
        );
        optics.proximity_dark_counts + optics.proximity_peak_counts * view.intensity
    }
}

/// Squared quantile distance of one channel between the simulated traces under `optics` and
/// the real targets (mean over classes, directions and quantiles, counts²).
pub fn channel_loss(
    optics: &OpticsParams,
    static_mm: f64,
    traces: &[Trace],
    targets: &[ChannelQuantiles],
    channel: usize,
) -> f64 {
    let mut d = SquaredDistance::default();
    for t in targets.iter().filter(|t| t.channel == channel) {
        let Some(trace) = traces.iter().find(|tr| tr.label == t.label) else {
            continue;
        };
        // Every second sample: 200 Hz is plenty for quantiles and halves the cost.
        let all: Vec<(u8, f64)> = trace
            .samples
            .iter()
            .step_by(2)
            .map(|s| {
                (
                    direction_of(s),
                    optics.saturate(channel_value(optics, static_mm, trace, s, channel)),
                )
            })
            .collect();
        // The deformation channels relative to the recording's median, as the targets.
        let shift = if channel < 3 {
            sorted_finite(all.iter().map(|a| a.1).collect()).map_or(0.0, |v| v[v.len() / 2])
        } else {
            0.0
        };
        let values: Vec<f64> = all
            .iter()
            .filter(|a| a.0 == t.direction)
            .map(|a| a.1 - shift)
            .collect();
        // Targets with the proximity tails ([`P_TAILS`]) are compared at those levels too.
        let q = if t.values.len() == QUANTILES.len() + P_TAILS.len() {
            quantiles_at(values, &levels_with_tails())
        } else {
            quantiles(values)
        };
        d.add(&q, &t.values);
    }
    d.mean()
}

/// Minimises `f` from `x0` with initial simplex steps `step` by Nelder–Mead, for at most
/// `max_evals` evaluations. Returns the best point and its value.
pub fn nelder_mead(
    mut f: impl FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: &[f64],
    max_evals: usize,
) -> (Vec<f64>, f64) {
    let n = x0.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    let v0 = f(x0);
    simplex.push((x0.to_vec(), v0));
    for i in 0..n {
        let mut x = x0.to_vec();
        x[i] += step[i];
        let v = f(&x);
        simplex.push((x, v));
    }
    let mut evals = n + 1;
    let sanitize = |v: f64| if v.is_finite() { v } else { f64::MAX };
    for s in &mut simplex {
        s.1 = sanitize(s.1);
    }
    while evals < max_evals {
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let best = simplex[0].1;
        let worst = simplex[n].1;
        if (worst - best).abs() <= 1e-9 * (1.0 + best.abs()) {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|i| simplex[..n].iter().map(|s| s.0[i]).sum::<f64>() / n as f64)
            .collect();
        let towards = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|i| centroid[i] + t * (simplex[n].0[i] - centroid[i]))
                .collect()
        };
        let xr = towards(-1.0);
        let vr = sanitize(f(&xr));
        evals += 1;
        if vr < simplex[0].1 {
            let xe = towards(-2.0);
            let ve = sanitize(f(&xe));
            evals += 1;
            simplex[n] = if ve < vr { (xe, ve) } else { (xr, vr) };
        } else if vr < simplex[n - 1].1 {
            simplex[n] = (xr, vr);
        } else {
            let xc = if vr < simplex[n].1 {
                towards(-0.5)
            } else {
                towards(0.5)
            };
            let vc = sanitize(f(&xc));
            evals += 1;
            if vc < simplex[n].1.min(vr) {
                simplex[n] = (xc, vc);
            } else {
                // Shrink towards the best point.
                let best_x = simplex[0].0.clone();
                for s in simplex.iter_mut().skip(1) {
                    for (x, b) in s.0.iter_mut().zip(&best_x) {
                        *x = b + 0.5 * (*x - b);
                    }
                    s.1 = sanitize(f(&s.0));
                    evals += 1;
                }
            }
        }
    }
    simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (x, v) = simplex.swap_remove(0);
    (x, v)
}

/// What a calibration did.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationReport {
    /// Quantile distance (RMS, counts) per channel before the fit (D1, D2, D3, P), with the
    /// starting sensor and geometry, over both experiments.
    pub rms_before: [f64; 4],
    /// After the fit.
    pub rms_after: [f64; 4],
    /// Tip-speed quantile distance ([`speed_loss`], RMS, mm/s) before the fit.
    pub speed_rms_before: f64,
    /// After the fit.
    pub speed_rms_after: f64,
    /// White-noise levels measured on the real flat recordings, counts.
    pub noise_counts: [f64; 4],
    /// The fitted optics.
    pub optics: OpticsParams,
    /// The fitted finger mechanics.
    pub finger: FingerParams,
    /// The plates' fitted geometry.
    pub samples: Samples,
    /// Every mechanics candidate tried, in [`MECHANICS`] order, with its weighted loss.
    pub candidates: Vec<(Vec<f64>, f64)>,
}

/// The mechanical and geometric parameters [`calibrate`] fits (with the optics refitted for
/// each candidate), in the order of [`CalibrationReport::candidates`].
pub const MECHANICS: [&str; 7] = [
    "finger.tip_radius_mm",
    "finger.lateral_stiffness_n_mm",
    "finger.friction",
    "samples.crack_depth_mm",
    "samples.bump_radius_mm",
    "samples.bump_height_mm",
    "samples.crack_wall_angle_deg",
];

/// Slides per simulated recording while fitting (the statistics settle after a few).
pub const CALIBRATION_SLIDES: u32 = 4;

/// The values of [`MECHANICS`] in `config`.
pub fn mechanics_of(config: &ExperimentConfig) -> [f64; 7] {
    let f = &config.sensor.finger;
    let s = &config.samples;
    [
        f.tip_radius_mm,
        f.lateral_stiffness_n_mm,
        f.friction,
        s.crack_depth_mm,
        s.bump_radius_mm,
        s.bump_height_mm,
        s.crack_wall_angle_deg,
    ]
}

/// `config` with the [`MECHANICS`] values `m`.
pub fn with_mechanics(config: &ExperimentConfig, m: &[f64]) -> ExperimentConfig {
    let mut c = config.clone();
    c.sensor.finger.tip_radius_mm = m[0];
    c.sensor.finger.lateral_stiffness_n_mm = m[1];
    c.sensor.finger.friction = m[2];
    c.samples.crack_depth_mm = m[3];
    c.samples.bump_radius_mm = m[4];
    c.samples.bump_height_mm = m[5];
    c.samples.crack_wall_angle_deg = m[6].min(90.0);
    c
}

/// One experiment's share of a calibration: simulated recordings and the real targets.
struct Set {
    traces: Vec<Trace>,
    targets: Vec<ChannelQuantiles>,
    speed_targets: Vec<(f64, Vec<f64>)>,
}

/// Root mean square tip-speed distance over the sets, mm/s.
fn sets_speed_rms(sets: &[Set]) -> f64 {
    (sets
        .iter()
        .map(|s| speed_loss(&s.traces, &s.speed_targets))
        .sum::<f64>()
        / sets.len().max(1) as f64)
        .sqrt()
}

fn sets_loss(o: &OpticsParams, static_mm: f64, sets: &[Set], channel: usize) -> f64 {
    sets.iter()
        .map(|s| channel_loss(o, static_mm, &s.traces, &s.targets, channel))
        .sum::<f64>()
        / sets.len().max(1) as f64
}

fn sets_rms(o: &OpticsParams, static_mm: f64, sets: &[Set]) -> [f64; 4] {
    std::array::from_fn(|c| sets_loss(o, static_mm, sets, c).sqrt())
}

/// The single number the mechanics search minimises: squared quantile distances, the lateral
/// channels D1 and D2 (which the classifiers read) weighted 10, D3 3, P 1 (its excursions are
/// tens of times larger).
pub fn weighted_loss(rms: &[f64; 4]) -> f64 {
    10.0 * (rms[0].powi(2) + rms[1].powi(2)) + 3.0 * rms[2].powi(2) + rms[3].powi(2)
}

/// Fits the deformation gains (lateral, normal, moment) of channel `c` by Nelder–Mead.
fn fit_deformation(
    optics: &mut OpticsParams,
    static_mm: f64,
    sets: &[Set],
    c: usize,
    max_evals: usize,
) {
    let x0 = [
        optics.lateral_gain[c],
        optics.normal_gain[c],
        optics.moment_gain[c],
    ];
    let (x, _) = nelder_mead(
        |x| {
            let mut o = optics.clone();
            o.lateral_gain[c] = x[0];
            o.normal_gain[c] = x[1];
            o.moment_gain[c] = x[2];
            sets_loss(&o, static_mm, sets, c)
        },
        &x0,
        &[5.0, 5.0, 2.0],
        max_evals,
    );
    optics.lateral_gain[c] = x[0];
    optics.normal_gain[c] = x[1];
    optics.moment_gain[c] = x[2];
}

/// Fits the proximity optics (dark level, peak, peak distance, fibre height, look-ahead, spot)
/// to the real quantiles from the given `(look-ahead, fibre height)` starts (mm); returns the
/// best optics and its RMS.
fn fit_proximity(
    start: &OpticsParams,
    static_mm: f64,
    sets: &[Set],
    starts: &[(f64, f64)],
    max_evals: usize,
    rules: ProximityRules,
) -> (OpticsParams, f64) {
    // x = [peak counts, peak distance, height, look-ahead, spot] (+ the dark level when fitted)
    // (+ the cone's half-angle when the start traces rays, `proximity_cone_deg` > 0).
    let fit_dark = !rules.measured_dark;
    let fit_cone = start.proximity_cone_deg > 0.0;
    let apply = |o: &mut OpticsParams, x: &[f64]| {
        o.proximity_peak_counts = x[0];
        o.proximity_peak_mm = x[1].max(0.05);
        o.proximity_height_mm = x[2];
        o.proximity_offset_mm = x[3];
        o.proximity_spot_mm = x[4].abs();
        let mut next = 5;
        if fit_dark {
            o.proximity_dark_counts = x[next];
            next += 1;
        }
        if fit_cone {
            o.proximity_cone_deg = x[next].clamp(1.0, 60.0);
        }
    };
    let mut best = (start.clone(), f64::INFINITY);
    // Look-ahead behind, under and ahead of the tip; the fibre on either side of the curve's peak.
    for &(offset, height) in starts {
        let mut x0 = vec![
            start.proximity_peak_counts,
            start.proximity_peak_mm,
            height,
            offset,
            start.proximity_spot_mm,
        ];
        let mut steps = vec![50.0, 0.3, 0.5, 0.5, 0.3];
        if fit_dark {
            x0.push(start.proximity_dark_counts);
            steps.push(20.0);
        }
        if fit_cone {
            x0.push(start.proximity_cone_deg);
            steps.push(8.0);
        }
        let (x, v) = nelder_mead(
            |x| {
                let mut o = start.clone();
                apply(&mut o, x);
                if rules.far_branch && o.proximity_height_mm < o.proximity_peak_mm {
                    return f64::INFINITY;
                }
                if o.proximity_spot_mm < rules.min_spot_mm {
                    return f64::INFINITY;
                }
                sets_loss(&o, static_mm, sets, 3)
            },
            &x0,
            &steps,
            max_evals,
        );
        if v < best.1 {
            let mut o = start.clone();
            apply(&mut o, &x);
            best = (o, v);
        }
    }
    (best.0, best.1.sqrt())
}

/// Constraints on the proximity fit ([`SearchSettings`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProximityRules {
    /// The dark level is measured ([`real_dark_counts`]), not fitted: the quantiles barely see
    /// the short dips into the dark, and a free dark level can settle far above the real one.
    pub measured_dark: bool,
    /// The fibre works on the far side of its curve's peak (height ≥ peak distance), where the
    /// reading falls as the surface recedes: the real proximity drops straight into the dark
    /// over a crack, it never first rises.
    pub far_branch: bool,
    /// The proximity channel is also compared at the low tail quantiles [`P_TAILS`], where the
    /// short dips into the dark over narrow cracks show.
    pub tails: bool,
    /// The proximity fibre's spot is at least this wide, mm (0: no bound). The wavy plate's
    /// flat real reading rules out a pinpoint spot far above the surface.
    pub min_spot_mm: f64,
}

/// Fits the optics to `sets` for fixed mechanics: the proximity channel from `starts`, then
/// each deformation channel. Returns the optics and the RMS per channel.
fn fit_optics(
    start: &OpticsParams,
    static_mm: f64,
    sets: &[Set],
    starts: &[(f64, f64)],
    max_evals: usize,
    rules: ProximityRules,
) -> (OpticsParams, [f64; 4]) {
    let (mut optics, _) = fit_proximity(start, static_mm, sets, starts, max_evals, rules);
    for c in 0..3 {
        fit_deformation(&mut optics, static_mm, sets, c, max_evals / 2);
    }
    let rms = sets_rms(&optics, static_mm, sets);
    (optics, rms)
}

/// Fits the finger's mechanics, the plates' geometry and the optics of `config` to real
/// recordings of the recognition experiment (`recognition`, labels 0–3) and, when given, of
/// the width experiment (`width`). Every candidate of [`MECHANICS`] (searched by Nelder–Mead in
/// log space from `config`'s values, at most `mechanics_evals` candidates) gets its recordings
/// simulated ([`CALIBRATION_SLIDES`] slides per plate, noise-free) and its optics refitted
/// from the starting optics (`max_evals / 3` evaluations per Nelder–Mead run); the best one
/// then gets its optics fitted from several starts with `max_evals`. The deformation channels'
/// resting levels are set so that the simulated flat plate has the real one's medians.
/// `progress(done, total)` is called per candidate.
#[expect(
    clippy::too_many_lines,
    reason = "the calibration procedure, one fit after another over shared intermediates; not yet split into steps"
)]
pub fn calibrate(
    config: &ExperimentConfig,
    recognition: &[Recording],
    width: Option<&[Recording]>,
    search: &SearchSettings,
    mut progress: impl FnMut(usize, usize),
) -> Result<CalibrationReport, SimError> {
    let free = search.free_mask()?;
    let (max_evals, mechanics_evals, speed_weight) = (
        search.evaluations,
        search.mechanics_evaluations,
        search.speed_weight,
    );
    if recognition.is_empty() {
        return Err(SimError::NoRealRecordings);
    }
    let mut experiments = vec![(
        Experiment::Recognition,
        real_quantiles_with(recognition, search.proximity.tails),
        real_speed_quantiles(recognition),
    )];
    if let Some(w) = width.filter(|w| !w.is_empty()) {
        experiments.push((
            Experiment::Width,
            real_quantiles_with(w, search.proximity.tails),
            real_speed_quantiles(w),
        ));
    }
    let static_mm = static_of(config);
    let mut quiet = config.clone();
    quiet.integrator = Integrator::default();
    quiet.mounts.clear();
    quiet.slides = CALIBRATION_SLIDES;
    let sets_of = |c: &ExperimentConfig| -> Result<Vec<Set>, SimError> {
        experiments
            .iter()
            .map(|(e, targets, speed_targets)| {
                let mut c = c.clone();
                c.experiment = *e;
                Ok(Set {
                    traces: simulate_traces(&c)?,
                    targets: targets.clone(),
                    speed_targets: speed_targets.clone(),
                })
            })
            .collect()
    };
    let start_sets = sets_of(&quiet)?;
    let mut start_optics = config.sensor.optics.clone();
    let all_real: Vec<&Recording> = recognition.iter().chain(width.unwrap_or(&[])).collect();
    let rules = search.proximity;
    if let Some(dark) = real_dark_counts(&all_real).filter(|_| rules.measured_dark) {
        start_optics.proximity_dark_counts = dark;
    }
    let rms_before = sets_rms(&config.sensor.optics, static_mm, &start_sets);
    let speed_rms_before = sets_speed_rms(&start_sets);
    let one_start = [(
        config.sensor.optics.proximity_offset_mm,
        config.sensor.optics.proximity_height_mm,
    )];
    let (start_optics, _) = fit_optics(
        &start_optics,
        static_mm,
        &start_sets,
        &one_start,
        max_evals,
        rules,
    );
    let m0 = mechanics_of(&quiet);
    let total = mechanics_evals.max(1);
    let mut candidates: Vec<(Vec<f64>, f64)> = Vec::new();
    let mut failure: Option<SimError> = None;
    // The search runs over the free parameters only (log space); the fixed ones keep m0.
    let free_idx: Vec<usize> = (0..m0.len()).filter(|&k| free[k]).collect();
    let full = |x: &[f64]| -> Vec<f64> {
        let mut m = m0.to_vec();
        for (&k, v) in free_idx.iter().zip(x) {
            m[k] = v.exp();
        }
        m
    };
    const STEPS: [f64; 7] = [0.3, 0.5, 0.4, 0.3, 0.2, 0.2, 0.15];
    let (best_log, _) = nelder_mead(
        |x| {
            let m = full(x);
            let trial = with_mechanics(&quiet, &m);
            let loss = match trial.validate().and_then(|()| sets_of(&trial)) {
                Ok(sets) => {
                    let (_, rms) = fit_optics(
                        &start_optics,
                        static_mm,
                        &sets,
                        &one_start,
                        max_evals / 3,
                        rules,
                    );
                    weighted_loss(&rms) + speed_weight * sets_speed_rms(&sets).powi(2)
                }
                // Mechanics out of range (a validation refusing them): not a candidate.
                Err(SimError::Setting { .. }) => f64::INFINITY,
                Err(e) => {
                    failure.get_or_insert(e);
                    f64::INFINITY
                }
            };
            candidates.push((m, loss));
            progress(candidates.len().min(total), total);
            loss
        },
        &free_idx.iter().map(|&k| m0[k].ln()).collect::<Vec<_>>(),
        &free_idx.iter().map(|&k| STEPS[k]).collect::<Vec<_>>(),
        total,
    );
    if let Some(e) = failure {
        return Err(e);
    }
    let best = full(&best_log);
    let fitted = with_mechanics(&quiet, &best);
    let sets = sets_of(&fitted)?;
    let (mut optics, _) = fit_optics(
        &start_optics,
        static_mm,
        &sets,
        &[
            (
                start_optics.proximity_offset_mm,
                start_optics.proximity_height_mm,
            ),
            (-1.5, 1.5),
            (0.0, 1.5),
            (1.5, 1.5),
            (0.0, 3.5),
        ],
        max_evals,
        rules,
    );
    // Resting levels: the simulated flat plate's medians onto the real one's.
    let real_flat: Vec<Recording> = recognition
        .iter()
        .filter(|r| r.label() == Some(0.0))
        .cloned()
        .collect();
    if let (Some(flat), Some(real)) = (
        sets[0].traces.iter().find(|t| t.label == 0.0),
        real_flat.first().and_then(recording_medians),
    ) {
        for (c, real_median) in real.iter().take(3).enumerate() {
            let sim = sorted_finite(
                flat.samples
                    .iter()
                    .map(|s| channel_value(&optics, static_mm, flat, s, c))
                    .collect(),
            );
            if let Some(sim) = sim {
                optics.rest_counts[c] += real_median - sim[sim.len() / 2];
            }
        }
    }
    let noise_counts = real_noise(recognition);
    optics.noise_counts = noise_counts;
    Ok(CalibrationReport {
        rms_before,
        rms_after: sets_rms(&optics, static_mm, &sets),
        speed_rms_before,
        speed_rms_after: sets_speed_rms(&sets),
        noise_counts,
        optics,
        finger: fitted.sensor.finger.clone(),
        samples: fitted.samples.clone(),
        candidates,
    })
}

/// The quantile distance (RMS counts per channel, D1, D2, D3, P) between `config`'s sensor and
/// plates (noise-free, [`CALIBRATION_SLIDES`] slides per plate, neutral mounts) and real
/// recordings of the recognition experiment and, when given, of the width experiment: the
/// numbers [`calibrate`] reports as `rms_after`.
pub fn fit_rms(
    config: &ExperimentConfig,
    recognition: &[Recording],
    width: Option<&[Recording]>,
) -> Result<[f64; 4], SimError> {
    let sets = fit_sets(config, recognition, width)?;
    Ok(sets_rms(&config.sensor.optics, static_of(config), &sets))
}

/// The tip-speed distance (RMS of [`speed_loss`], mm/s) between `config`'s finger and the real
/// recordings, over the same simulated recordings as [`fit_rms`]: the number [`calibrate`]
/// reports as `speed_rms_after`.
pub fn fit_speed_rms(
    config: &ExperimentConfig,
    recognition: &[Recording],
    width: Option<&[Recording]>,
) -> Result<f64, SimError> {
    Ok(sets_speed_rms(&fit_sets(config, recognition, width)?))
}

/// Static compression of the normal spring under the body's weight, mm.
fn static_of(config: &ExperimentConfig) -> f64 {
    let s = &config.sensor.finger;
    s.body_mass_g * 1e-3 * 9.81 / (s.normal_stiffness_n_mm * 1e3) * 1e3
}

fn fit_sets(
    config: &ExperimentConfig,
    recognition: &[Recording],
    width: Option<&[Recording]>,
) -> Result<Vec<Set>, SimError> {
    let mut quiet = config.clone();
    quiet.mounts.clear();
    quiet.slides = CALIBRATION_SLIDES;
    let mut sets = Vec::new();
    for (experiment, real) in [
        (Experiment::Recognition, Some(recognition)),
        (Experiment::Width, width),
    ] {
        let Some(real) = real.filter(|r| !r.is_empty()) else {
            continue;
        };
        quiet.experiment = experiment;
        sets.push(Set {
            traces: simulate_traces(&quiet)?,
            targets: real_quantiles(real),
            speed_targets: real_speed_quantiles(real),
        });
    }
    Ok(sets)
}

/// The roughness (height rms, mm) that gives the real flat plate's proximity spread: the
/// spread of P on the real flat recordings (label 0) beyond the white noise, divided by the
/// proximity curve's slope at the flat contact distance under `optics`.
pub fn fit_roughness(optics: &OpticsParams, real: &[Recording]) -> f64 {
    let p: Vec<f64> = real
        .iter()
        .filter(|r| r.label() == Some(0.0))
        .flat_map(|r| r.rows.iter().map(|row| row.p))
        .collect();
    if p.len() < 2 {
        return 0.0;
    }
    let mean = p.iter().sum::<f64>() / p.len() as f64;
    let var = p.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (p.len() - 1) as f64;
    let excess = (var - optics.noise_counts[3].powi(2)).max(0.0).sqrt();
    let d = optics.proximity_height_mm;
    let h = 1e-3;
    let slope = optics.proximity_peak_counts
        * (optics.proximity_curve(d + h) - optics.proximity_curve(d - h))
        / (2.0 * h);
    if slope.abs() < 1e-9 {
        0.0
    } else {
        excess / slope.abs()
    }
}

/// White noise per channel of the real flat recordings (label 0): the standard deviation of
/// first differences over √2, from a robust (median absolute) estimate.
pub fn real_noise(real: &[Recording]) -> [f64; 4] {
    std::array::from_fn(|c| {
        let mut diffs: Vec<f64> = real
            .iter()
            .filter(|r| r.label() == Some(0.0))
            .flat_map(|r| {
                r.rows
                    .windows(2)
                    .map(move |w| {
                        let a = w[0].channels()[c];
                        let b = w[1].channels()[c];
                        b - a
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        if diffs.is_empty() {
            return 0.0;
        }
        diffs.sort_by(f64::total_cmp);
        // Mean absolute difference is robust enough and, unlike the median, not zero for
        // quantised signals that mostly repeat a code.
        let mad = diffs.iter().map(|d| d.abs()).sum::<f64>() / diffs.len() as f64;
        // For Gaussian noise E|Δ| = 2σ/√π.
        mad * std::f64::consts::PI.sqrt() / 2.0
    })
}

/// What `crackbot sim calibrate` finds: the fit of the optics and geometry, and the plate
/// mounts of each experiment fitted with it (`("recognition", …)`, then `("width", …)` when
/// width recordings were given).
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationSummary {
    /// The fit.
    pub report: CalibrationReport,
    /// Per experiment, its plates' mounts in the order of `ExperimentConfig::surfaces`.
    pub mounts: Vec<(String, Vec<PlateMount>)>,
}

/// Where a calibration starts: the paper's recognition experiment (seed 7) with the calibrated
/// sensor and geometry and neutral mounts (a refit moves from the last fit).
pub fn starting_config() -> ExperimentConfig {
    let mut config = ExperimentConfig::paper(Experiment::Recognition, 7);
    config.mounts.clear();
    config
}

/// Calibrates the simulated sensor on real recordings: [`calibrate`] from `start` (usually
/// [`starting_config`]) on
/// the `recognition` and (when given) `width` recordings (at most `evaluations` per
/// Nelder–Mead run of the optics and `mechanics_evaluations` mechanics candidates, `progress`
/// as [`calibrate`] calls it), the roughness of the flat plate ([`fit_roughness`]), then the
/// plate mounts of both experiments with the fitted sensor and geometry.
pub fn calibrate_to_real(
    start: &ExperimentConfig,
    recognition: &[Recording],
    width: Option<&[Recording]>,
    search: &SearchSettings,
    progress: impl FnMut(usize, usize),
) -> Result<CalibrationSummary, SimError> {
    let config = start.clone();
    let mut report = calibrate(&config, recognition, width, search, progress)?;
    report.samples.roughness_rms_mm = fit_roughness(&report.optics, recognition);
    let mut calibrated = config;
    calibrated.sensor.optics = report.optics.clone();
    calibrated.sensor.finger = report.finger.clone();
    calibrated.samples = report.samples.clone();
    let mut mounts = vec![(
        "recognition".to_string(),
        fit_mounts(&calibrated, recognition)?,
    )];
    if let Some(width_real) = width {
        let mut width_config = calibrated.clone();
        width_config.experiment = Experiment::Width;
        mounts.push(("width".to_string(), fit_mounts(&width_config, width_real)?));
    }
    Ok(CalibrationSummary { report, mounts })
}
