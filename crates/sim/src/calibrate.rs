//! Calibration of the simulated sensor against the authors' real recordings.
//!
//! The mechanics are physical guesses (the finger's stiffness, friction and geometry are not
//! published); the optics and electronics are *fitted*: the simulator runs the recognition
//! experiment once with noise-free electronics, and the channel maps are chosen so that, for
//! every surface class and sliding direction, the quantiles (5 %, 15 %, …, 95 %) of each
//! simulated channel match those of the real recordings. That needs no alignment between real
//! and simulated slides (the real feature positions are unknown), and it matches signal levels
//! and per-class shapes of the distributions. The deformation channels are linear in their
//! parameters (rest level and gains for lateral deflection, normal compression and friction
//! moment) and are fitted one by one; the proximity channel (dark level, peak, peak distance,
//! fibre height, look-ahead, spot) is fitted jointly. Both by Nelder–Mead. Noise levels come
//! from the first differences of the real flat recordings.
//!
//! [`calibrated_sensor`] holds the result of `crackbot sim calibrate` on repetition 1 of
//! `../shared/data/tactile/type` (repetitions 2 and 3 are left for checking the sim→real
//! transfer).

use crackbot_recording::Recording;
use serde::Serialize;

use crate::experiment::ExperimentConfig;
use crate::finger::{FingerModel, Integrator};
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
            .map(|row| row.channels())
            .collect();
        if rows.is_empty() {
            return Err(SimError::Invalid(format!(
                "no real recording of the plate labelled {} to fit its mount to",
                trace.label
            )));
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
    /// Sliding direction (1 = +x).
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
    match sorted_finite(v) {
        Some(v) => QUANTILES
            .iter()
            .map(|q| v[((v.len() - 1) as f64 * q).round() as usize])
            .collect(),
        None => vec![0.0; QUANTILES.len()],
    }
}

/// The real targets: channel quantiles per class and direction, from `recordings` (each with
/// its label in the rows).
pub fn real_quantiles(recordings: &[Recording]) -> Vec<ChannelQuantiles> {
    let mut labels: Vec<f64> = recordings.iter().filter_map(|r| r.label()).collect();
    labels.sort_by(f64::total_cmp);
    labels.dedup();
    let mut out = Vec::new();
    for &label in &labels {
        for direction in [0u8, 1] {
            for channel in 0..4 {
                let values = recordings
                    .iter()
                    .flat_map(|r| r.rows.iter())
                    .filter(|row| row.label == label && row.direction == direction)
                    .map(|row| row.channels()[channel])
                    .collect();
                out.push(ChannelQuantiles {
                    label,
                    direction,
                    channel,
                    values: quantiles(values),
                });
            }
        }
    }
    out
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

/// Simulates one recording per surface of `config` (12 slides, noise-free electronics) for
/// calibration.
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

fn direction_of(s: &Sample) -> u8 {
    u8::from(s.arm_velocity_mm_s >= 0.0)
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
    let mut total = 0.0;
    let mut n = 0usize;
    for t in targets.iter().filter(|t| t.channel == channel) {
        let Some(trace) = traces.iter().find(|tr| tr.label == t.label) else {
            continue;
        };
        // Every second sample: 200 Hz is plenty for quantiles and halves the cost.
        let values: Vec<f64> = trace
            .samples
            .iter()
            .step_by(2)
            .filter(|s| direction_of(s) == t.direction)
            .map(|s| optics.saturate(channel_value(optics, static_mm, trace, s, channel)))
            .collect();
        let q = quantiles(values);
        for (a, b) in q.iter().zip(&t.values) {
            total += (a - b).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        total / n as f64
    }
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
    for s in simplex.iter_mut() {
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
    /// starting optics and geometry.
    pub rms_before: [f64; 4],
    /// After the fit.
    pub rms_after: [f64; 4],
    /// White-noise levels measured on the real flat recordings, counts.
    pub noise_counts: [f64; 4],
    /// The fitted optics.
    pub optics: OpticsParams,
    /// The plates' geometry chosen from the grid.
    pub samples: Samples,
    /// Proximity distance (RMS counts) of every geometry tried: `(crack depth, bump radius,
    /// bump height, RMS)`.
    pub geometry_grid: Vec<(f64, f64, f64, f64)>,
}

/// Geometries tried by [`calibrate`]: crack depths, bump radii and bump heights, mm.
pub const GEOMETRY_GRID: ([f64; 3], [f64; 4], [f64; 3]) =
    ([3.0, 5.0, 8.0], [2.0, 3.0, 4.5, 6.0], [1.0, 2.0, 3.5]);

/// Fits the proximity optics (dark level, peak, peak distance, fibre height, look-ahead, spot)
/// to the real quantiles from a few starting points; returns the best optics and its RMS.
fn fit_proximity(
    start: &OpticsParams,
    static_mm: f64,
    traces: &[Trace],
    targets: &[ChannelQuantiles],
    max_evals: usize,
) -> (OpticsParams, f64) {
    let apply = |o: &mut OpticsParams, x: &[f64]| {
        o.proximity_dark_counts = x[0];
        o.proximity_peak_counts = x[1];
        o.proximity_peak_mm = x[2].max(0.05);
        o.proximity_height_mm = x[3];
        o.proximity_offset_mm = x[4];
        o.proximity_spot_mm = x[5].abs();
    };
    let mut best = (start.clone(), f64::INFINITY);
    // Look-ahead behind, under and ahead of the tip; the fibre on either side of the curve's peak.
    for (offset, height) in [(-1.5, 1.5), (0.0, 1.5), (1.5, 1.5), (0.0, 3.5)] {
        let x0 = [
            start.proximity_dark_counts,
            start.proximity_peak_counts,
            start.proximity_peak_mm,
            height,
            offset,
            start.proximity_spot_mm,
        ];
        let (x, v) = nelder_mead(
            |x| {
                let mut o = start.clone();
                apply(&mut o, x);
                channel_loss(&o, static_mm, traces, targets, 3)
            },
            &x0,
            &[20.0, 50.0, 0.3, 0.5, 0.5, 0.3],
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

/// Fits the optics of `config.sensor` and the plates' geometry to `real` recordings of the
/// recognition experiment (labels 0–3): for every geometry of [`GEOMETRY_GRID`] the proximity
/// optics are fitted from several starts; the best geometry then gets its deformation channels
/// fitted. `max_evals` bounds each Nelder–Mead run; `progress(done, total)` is called per
/// geometry.
pub fn calibrate(
    config: &ExperimentConfig,
    real: &[Recording],
    max_evals: usize,
    mut progress: impl FnMut(usize, usize),
) -> Result<CalibrationReport, SimError> {
    if config.experiment != Experiment::Recognition {
        return Err(SimError::Invalid(
            "calibration uses the recognition experiment (four surfaces)".into(),
        ));
    }
    if real.is_empty() {
        return Err(SimError::Invalid(
            "no real recordings to calibrate against".into(),
        ));
    }
    let targets = real_quantiles(real);
    let static_mm = {
        let s = &config.sensor.finger;
        s.body_mass_g * 1e-3 * 9.81 / (s.normal_stiffness_n_mm * 1e3) * 1e3
    };
    let rms = |o: &OpticsParams, traces: &[Trace]| -> [f64; 4] {
        std::array::from_fn(|c| channel_loss(o, static_mm, traces, &targets, c).sqrt())
    };
    let mut quiet = config.clone();
    quiet.integrator = Integrator::default();
    quiet.mounts.clear();
    let rms_before = rms(&config.sensor.optics, &simulate_traces(&quiet)?);
    let (depths, radii, heights) = GEOMETRY_GRID;
    let total = depths.len() * radii.len() * heights.len();
    let mut grid = Vec::with_capacity(total);
    let mut best: Option<(f64, Samples, OpticsParams, Vec<Trace>)> = None;
    for &depth in &depths {
        for &radius in &radii {
            for &height in &heights {
                let mut trial = quiet.clone();
                trial.samples.crack_depth_mm = depth;
                trial.samples.bump_radius_mm = radius;
                trial.samples.bump_height_mm = height;
                let traces = simulate_traces(&trial)?;
                let (optics, p_rms) = fit_proximity(
                    &config.sensor.optics,
                    static_mm,
                    &traces,
                    &targets,
                    max_evals,
                );
                grid.push((depth, radius, height, p_rms));
                progress(grid.len(), total);
                if best.as_ref().is_none_or(|b| p_rms < b.0) {
                    best = Some((p_rms, trial.samples.clone(), optics, traces));
                }
            }
        }
    }
    let Some((_, samples, mut optics, traces)) = best else {
        return Err(SimError::Invalid("empty geometry grid".into()));
    };
    for c in 0..3 {
        let x0 = [
            optics.rest_counts[c],
            optics.lateral_gain[c],
            optics.normal_gain[c],
            optics.moment_gain[c],
        ];
        let (x, _) = nelder_mead(
            |x| {
                let mut o = optics.clone();
                o.rest_counts[c] = x[0];
                o.lateral_gain[c] = x[1];
                o.normal_gain[c] = x[2];
                o.moment_gain[c] = x[3];
                channel_loss(&o, static_mm, &traces, &targets, c)
            },
            &x0,
            &[5.0, 5.0, 5.0, 5.0],
            max_evals,
        );
        optics.rest_counts[c] = x[0];
        optics.lateral_gain[c] = x[1];
        optics.normal_gain[c] = x[2];
        optics.moment_gain[c] = x[3];
    }
    let noise_counts = real_noise(real);
    optics.noise_counts = noise_counts;
    Ok(CalibrationReport {
        rms_before,
        rms_after: rms(&optics, &traces),
        noise_counts,
        optics,
        samples,
        geometry_grid: grid,
    })
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

/// Where a calibration starts: the paper's recognition experiment (seed 7) with first-guess
/// optics, the default plate geometry and neutral mounts.
pub fn starting_config() -> ExperimentConfig {
    let mut config = ExperimentConfig::paper(Experiment::Recognition, 7);
    config.sensor.optics = OpticsParams::first_guess();
    config.samples = Samples::default();
    config.mounts.clear();
    config
}

/// Number of steps [`calibrate`] reports progress over (the geometries of [`GEOMETRY_GRID`]).
pub fn calibration_steps() -> usize {
    let (d, r, h) = GEOMETRY_GRID;
    d.len() * r.len() * h.len()
}

/// Calibrates the simulated sensor on real recordings: [`calibrate`] from [`starting_config`] on
/// the `recognition` recordings (at most `evaluations` per Nelder–Mead run, `progress` as
/// [`calibrate`] calls it), then the plate mounts of the recognition experiment and, given
/// `width` recordings, of the width experiment, with the fitted optics and geometry.
pub fn calibrate_to_real(
    recognition: &[Recording],
    width: Option<&[Recording]>,
    evaluations: usize,
    progress: impl FnMut(usize, usize),
) -> Result<CalibrationSummary, SimError> {
    let config = starting_config();
    let report = calibrate(&config, recognition, evaluations, progress)?;
    let mut calibrated = config;
    calibrated.sensor.optics = report.optics.clone();
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
