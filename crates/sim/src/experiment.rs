//! The paper's two experiments, simulated: recordings in the authors' nine-column format.
//!
//! * Recognition: four surfaces, label 0 flat, 1 crack, 2 bump, 3 wavy pattern; files
//!   `crack_{nocrack,crack,bump,pattern}_complete_<r>.csv`.
//! * Width: cracks of 0, 1, 2, 5, 8 and 10 mm, label = width; files
//!   `crack_mm<w>_complete_<r>.csv`.
//!
//! Each recording is 12 slides (a 16 mm stroke forth and back at 4.6 mm/s) starting a random
//! distance before the feature's near edge ([`paper_start_range_mm`]: 6–7.4 mm for recognition,
//! 5–10 mm for width), on a random line across the plate, with the
//! recording's own offset/gain change and noise. Everything follows from the seed: the same seed
//! writes the same bytes. The files load with `crackbot tactile eval` as they are.

use std::path::{Path, PathBuf};

use crackbot_recording::{write_recording, Recording, Row};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::finger::Integrator;
use crate::plates::{calibrated_mounts, calibrated_samples, calibrated_sensor};
pub use crate::plates::{Experiment, PlateMount, PrintedDecoy, PrintedSlot, Samples};
use crate::run::{SlideLine, SlideSim, SAMPLE_RATE_HZ};
use crate::surface::{Feature, Surface};
use crate::{list, SensorParams, SimError};

/// Sliding speed of the authors' recordings, mm/s: their 16 mm strokes take about 1,395 samples
/// at 400 Hz (repetition 1 of every plate, from the position column).
pub const PAPER_SPEED_MM_S: f64 = 4.6;

/// Where the strokes of `experiment` start by default, mm before the feature's near edge.
///
/// Width: the paper's "approximately 5–10 mm from the crack edge". Recognition: 6.0–7.4 mm,
/// the real onsets of repetition 1 read with the position column nearer the arm than the tip,
/// chosen among four ranges by how well a forest trained on simulation reads repetition 1
/// (`docs/calibration.md`, "Where the strokes start, again"); the width table could not choose
/// between readings, so width keeps the paper's range.
pub fn paper_start_range_mm(experiment: Experiment) -> (f64, f64) {
    match experiment {
        Experiment::Recognition => (6.0, 7.4),
        Experiment::Width => (5.0, 10.0),
    }
}

/// Settings of a simulated experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct ExperimentConfig {
    /// Which experiment.
    pub experiment: Experiment,
    /// Recordings per surface (the paper: 5).
    pub recordings: u32,
    /// Slides per recording (the paper: 12).
    pub slides: u32,
    /// Stroke length, mm.
    pub stroke_mm: f64,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f64,
    /// Range of the distance from the stroke's start to the feature's near edge, mm.
    pub start_range_mm: (f64, f64),
    /// Rate at which the position column is updated, Hz (the authors' haptic device: ~80 Hz;
    /// the value is held between updates).
    pub position_rate_hz: f64,
    /// The samples' geometry.
    pub samples: Samples,
    /// How each plate (in the order of [`ExperimentConfig::surfaces`]) sits under the sensor;
    /// empty for identical, neutral plates.
    pub mounts: Vec<PlateMount>,
    /// The sensor.
    pub sensor: SensorParams,
    /// The integrator.
    pub integrator: Integrator,
    /// Seed of everything random.
    pub seed: u64,
}

impl ExperimentConfig {
    /// The paper's settings for `experiment`, with the default sensor.
    pub fn paper(experiment: Experiment, seed: u64) -> Self {
        ExperimentConfig {
            experiment,
            recordings: 5,
            slides: 12,
            stroke_mm: 16.0,
            // The authors' files: 16 mm strokes of about 1,395 samples (repetition 1), 4.6 mm/s
            // (the paper's text says 3.89 mm/s on average).
            speed_mm_s: PAPER_SPEED_MM_S,
            start_range_mm: paper_start_range_mm(experiment),
            position_rate_hz: 80.0,
            samples: calibrated_samples(),
            sensor: calibrated_sensor(),
            mounts: calibrated_mounts(experiment),
            integrator: Integrator::default(),
            seed,
        }
    }

    /// Replaces the parameters that a TOML text names: any of the tables `[sensor.finger]`,
    /// `[sensor.optics]` (fields of [`FingerParams`](crate::FingerParams),
    /// [`OpticsParams`](crate::OpticsParams)), `[samples]` (fields of [`Samples`]) and
    /// `[mounts]` (`recognition` and `width`: each an array of
    /// [`PlateMount`](crate::plates::PlateMount)s, one per plate; this experiment's is used), as
    /// `crackbot sim calibrate --params-out` writes them; the fields it leaves out keep their
    /// values. Validates the result.
    pub fn apply_params_toml(&mut self, text: &str) -> Result<(), SimError> {
        let table = |table: &str, message: String| SimError::ParameterTable {
            table: table.to_string(),
            message,
        };
        let mut params: toml::Table = toml::from_str(text).map_err(|e| SimError::Parameters {
            message: e.to_string(),
        })?;
        let mut sensor = match params.remove("sensor") {
            Some(toml::Value::Table(t)) => t,
            Some(_) => return Err(table("sensor", "must be a table".into())),
            None => toml::Table::new(),
        };
        self.sensor.finger = overlay(
            &self.sensor.finger,
            sensor.remove("finger"),
            "sensor.finger",
        )?;
        self.sensor.optics = overlay(
            &self.sensor.optics,
            sensor.remove("optics"),
            "sensor.optics",
        )?;
        self.samples = overlay(&self.samples, params.remove("samples"), "samples")?;
        match params.remove("mounts") {
            None => {}
            Some(toml::Value::Table(mut per_experiment)) => {
                let key = match self.experiment {
                    Experiment::Recognition => "recognition",
                    Experiment::Width => "width",
                };
                if let Some(k) = per_experiment
                    .keys()
                    .find(|k| *k != "recognition" && *k != "width")
                {
                    return Err(table(
                        &format!("mounts.{k}"),
                        "unknown experiment (recognition or width)".into(),
                    ));
                }
                if let Some(v) = per_experiment.remove(key) {
                    self.mounts = v
                        .try_into()
                        .map_err(|e| table(&format!("mounts.{key}"), e.to_string()))?;
                }
            }
            Some(_) => return Err(table("mounts", "must be a table".into())),
        }
        let unknown = sensor
            .keys()
            .map(|k| format!("sensor.{k}"))
            .chain(params.keys().cloned())
            .next();
        if let Some(k) = unknown {
            return Err(table(
                &k,
                "unknown table (sensor.finger, sensor.optics, samples or mounts)".into(),
            ));
        }
        self.validate()
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<(), SimError> {
        for (name, n) in [("recordings", self.recordings), ("slides", self.slides)] {
            if n == 0 {
                return Err(SimError::setting(name, n, "≥ 1"));
            }
        }
        let (lo, hi) = self.start_range_mm;
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
            return Err(SimError::setting(
                "start_range_mm",
                list(&[lo, hi]),
                "[min, max] with 0 ≤ min ≤ max mm",
            ));
        }
        if !(self.position_rate_hz.is_finite() && self.position_rate_hz > 0.0) {
            return Err(SimError::setting(
                "position_rate_hz",
                self.position_rate_hz,
                "> 0 Hz",
            ));
        }
        self.validate_samples()?;
        self.validate_mounts()?;
        self.sensor.finger.validate()?;
        self.sensor.optics.validate()?;
        self.integrator.validate()
    }

    /// Checks the plates' depths, printed slots and printed decoys.
    fn validate_samples(&self) -> Result<(), SimError> {
        let s = &self.samples;
        // Every depth the plates are cut to, named as a parameter file names it.
        let slot_depths = s.printed_slots.iter().enumerate().map(|(k, slot)| {
            (
                format!("samples.printed_slots[{k}].depth_mm"),
                slot.depth_mm,
            )
        });
        let depths = [
            ("samples.crack_depth_mm".to_string(), Some(s.crack_depth_mm)),
            (
                "samples.width_crack_depth_mm".to_string(),
                s.width_crack_depth_mm,
            ),
        ]
        .into_iter()
        .chain(slot_depths);
        for (name, depth) in depths {
            if let Some(d) = depth.filter(|d| !(d.is_finite() && *d > 0.0)) {
                return Err(SimError::setting(name, d, "> 0 mm (a depth)"));
            }
        }
        for (k, slot) in s.printed_slots.iter().enumerate() {
            let name = format!("samples.printed_slots[{k}]");
            if !s.widths_mm.contains(&slot.nominal_mm) {
                return Err(SimError::setting(
                    format!("{name}.nominal_mm"),
                    slot.nominal_mm,
                    format!("one of samples.widths_mm {}", list(&s.widths_mm)),
                ));
            }
            if let Some(j) = s.printed_slots[..k]
                .iter()
                .position(|p| p.nominal_mm == slot.nominal_mm)
            {
                return Err(SimError::setting(
                    format!("{name}.nominal_mm"),
                    slot.nominal_mm,
                    format!(
                        "a plate not listed before (samples.printed_slots[{j}] lists it: it is \
                         listed twice)"
                    ),
                ));
            }
            if let Some(w) = slot.width_mm.filter(|w| !(w.is_finite() && *w >= 0.0)) {
                return Err(SimError::setting(format!("{name}.width_mm"), w, "≥ 0 mm"));
            }
        }
        for (k, d) in s.printed_decoys.iter().enumerate() {
            if self.experiment != Experiment::Recognition {
                return Err(SimError::setting(
                    "samples.printed_decoys",
                    format!("{} decoys", s.printed_decoys.len()),
                    "empty in the width experiment (printed decoys are plates of the \
                     recognition experiment only)",
                ));
            }
            if !(d.width_mm.is_finite() && d.width_mm > 0.0) {
                return Err(SimError::setting(
                    format!("samples.printed_decoys[{k}].width_mm"),
                    d.width_mm,
                    "> 0 mm",
                ));
            }
            if !(d.reflectivity.is_finite() && (0.0..=1.0).contains(&d.reflectivity)) {
                return Err(SimError::setting(
                    format!("samples.printed_decoys[{k}].reflectivity"),
                    d.reflectivity,
                    "within [0, 1]",
                ));
            }
        }
        Ok(())
    }

    /// Checks the plate mounts: one per plate (or none), finite offsets, reflectivity ≥ 0.
    fn validate_mounts(&self) -> Result<(), SimError> {
        let n = self.surfaces().len() - self.samples.printed_decoys.len();
        // The mounts are this experiment's table of a parameter file.
        let mounts = match self.experiment {
            Experiment::Recognition => "mounts.recognition",
            Experiment::Width => "mounts.width",
        };
        if !self.mounts.is_empty() && self.mounts.len() != n {
            return Err(SimError::setting(
                mounts,
                format!("{} plate mounts", self.mounts.len()),
                format!("one per plate ({n} plates), or none"),
            ));
        }
        for (k, m) in self.mounts.iter().enumerate() {
            if !m.offset_counts.iter().all(|v| v.is_finite()) {
                return Err(SimError::setting(
                    format!("{mounts}[{k}].offset_counts"),
                    list(&m.offset_counts),
                    "finite",
                ));
            }
            if !(m.reflectivity.is_finite() && m.reflectivity >= 0.0) {
                return Err(SimError::setting(
                    format!("{mounts}[{k}].reflectivity"),
                    m.reflectivity,
                    "≥ 0",
                ));
            }
        }
        Ok(())
    }

    /// The mount of plate `k` (neutral when none is given). The printed decoys, which follow the
    /// paper's plates, lie on the flat plate and take its mount.
    pub fn mount(&self, k: usize) -> PlateMount {
        let paper_plates = self.surfaces().len() - self.samples.printed_decoys.len();
        let k = if k >= paper_plates { 0 } else { k };
        self.mounts.get(k).copied().unwrap_or_default()
    }

    /// The surfaces of the experiment: `(file stem, label, surface, x of the feature's near
    /// edge in mm)`. The feature runs across the plate at x = 100 mm.
    pub fn surfaces(&self) -> Vec<(String, f64, Surface, f64)> {
        let s = &self.samples;
        let crack_of_depth = |w: f64, depth_mm: f64| Feature::Crack {
            path: vec![[100.0, 0.0], [100.0, 100.0]],
            width_mm: w,
            depth_mm,
            edge_radius_mm: 0.5,
            wall_angle_deg: s.crack_wall_angle_deg,
        };
        let crack = |w: f64| crack_of_depth(w, s.crack_depth_mm);
        let plate = |features: Vec<Feature>| Surface {
            size_mm: [200.0, 100.0],
            features,
        };
        match self.experiment {
            Experiment::Recognition => {
                let decoys = s.printed_decoys.iter().map(|d| {
                    (
                        format!(
                            "crack_printed_w{}_r{}",
                            fmt_width(d.width_mm),
                            fmt_width(d.reflectivity)
                        ),
                        0.0,
                        plate(vec![Feature::Decoy {
                            path: vec![[100.0, 0.0], [100.0, 100.0]],
                            width_mm: d.width_mm,
                            reflectivity: d.reflectivity,
                        }]),
                        100.0 - d.width_mm / 2.0,
                    )
                });
                let mut plates = vec![
                    ("crack_nocrack".into(), 0.0, plate(vec![]), 100.0),
                    (
                        "crack_crack".into(),
                        1.0,
                        plate(vec![crack(s.recognition_crack_width_mm)]),
                        100.0 - s.recognition_crack_width_mm / 2.0,
                    ),
                    (
                        "crack_bump".into(),
                        2.0,
                        plate(vec![Feature::Bump {
                            centre: [100.0, 50.0],
                            radius_mm: s.bump_radius_mm,
                            height_mm: s.bump_height_mm,
                        }]),
                        100.0 - s.bump_radius_mm,
                    ),
                    (
                        "crack_pattern".into(),
                        3.0,
                        plate(vec![Feature::Wavy {
                            min: [40.0, 0.0],
                            max: [160.0, 100.0],
                            amplitude_mm: s.wave_amplitude_mm,
                            period_mm: s.wave_period_mm,
                            direction_deg: 0.0,
                        }]),
                        100.0,
                    ),
                ];
                plates.extend(decoys);
                plates
            }
            Experiment::Width => s
                .widths_mm
                .iter()
                .map(|&w| {
                    // The label is the nominal width; the groove is cut to the printed slot.
                    let (cut, depth) = s.slot(w);
                    (
                        format!("crack_mm{}", fmt_width(w)),
                        w,
                        plate(vec![crack_of_depth(cut, depth)]),
                        100.0 - cut / 2.0,
                    )
                })
                .collect(),
        }
    }
}

/// `base` with the fields of the TOML table `over` replaced.
fn overlay<T: Serialize + serde::de::DeserializeOwned>(
    base: &T,
    over: Option<toml::Value>,
    what: &str,
) -> Result<T, SimError> {
    let invalid = |e: &dyn std::fmt::Display| SimError::ParameterTable {
        table: what.to_string(),
        message: e.to_string(),
    };
    let mut merged = toml::Value::try_from(base).map_err(|e| invalid(&e))?;
    match (merged.as_table_mut(), over) {
        (_, None) => {}
        (Some(table), Some(toml::Value::Table(over))) => table.extend(over),
        _ => return Err(invalid(&"must be a table")),
    }
    merged.try_into().map_err(|e| invalid(&e))
}

fn fmt_width(w: f64) -> String {
    if w.fract() == 0.0 {
        format!("{}", w as i64)
    } else {
        format!("{w}").replace('.', "p")
    }
}

/// Simulates one recording of `slides` slides over `surface` mounted as `mount`: the arm starts
/// `start_mm` before `edge_x` on the line y = `line_y`.
#[expect(
    clippy::too_many_arguments,
    reason = "each argument is one the step needs, and a struct would only rename them"
)]
pub fn simulate_recording(
    config: &ExperimentConfig,
    surface: &Surface,
    mount: PlateMount,
    label: f64,
    repetition: u32,
    edge_x: f64,
    start_mm: f64,
    line_y: f64,
    position_offset_mm: f64,
    seed: u64,
) -> Result<Recording, SimError> {
    let line = SlideLine {
        start: [edge_x - start_mm, line_y],
        direction: [1.0, 0.0],
        stroke_mm: config.stroke_mm,
        speed_mm_s: config.speed_mm_s,
    };
    let mut sensor = config.sensor.clone();
    for (rest, off) in sensor
        .optics
        .rest_counts
        .iter_mut()
        .zip(mount.offset_counts)
    {
        *rest += off;
    }
    let mut sim = SlideSim::new(
        surface,
        mount.reflectivity,
        &line,
        &sensor,
        config.integrator,
        seed,
    )?
    .with_roughness(
        config.samples.roughness_rms_mm,
        config.samples.roughness_correlation_mm,
        seed ^ 0x005e_ed0f_7e87_u64,
    )?;
    let slide_time = sim.slide_time();
    let n = (config.slides as f64 * slide_time * SAMPLE_RATE_HZ).round() as usize;
    let hold = (SAMPLE_RATE_HZ / config.position_rate_hz).round().max(1.0) as usize;
    let mut rows = Vec::with_capacity(n);
    let mut x_col = position_offset_mm;
    let mut last_dir = 0u8;
    for k in 0..n {
        let s = sim.next_sample()?;
        // The device's encoder reads where the sensor is, which lags the commanded path where
        // the finger sticks (the bump's stick-slip shows as a jump of the real position).
        if k % hold == 0 {
            x_col = position_offset_mm + s.tip_x_mm;
        }
        // The authors' convention (paper, and their files): 0 moving towards +x, 1 back.
        let direction = if s.arm_velocity_mm_s > 1e-9 {
            0
        } else if s.arm_velocity_mm_s < -1e-9 {
            1
        } else {
            last_dir
        };
        last_dir = direction;
        let slide = ((s.t - 0.5 / SAMPLE_RATE_HZ) / slide_time).floor() as u32 + 1;
        rows.push(Row {
            x_mm: (x_col * 1e4).round() / 1e4,
            d1: s.counts[0],
            d2: s.counts[1],
            d3: s.counts[2],
            p: s.counts[3],
            direction,
            slide: slide.min(config.slides),
            label,
            repetition,
        });
    }
    Ok(Recording { rows, extra: None })
}

/// One file written by [`generate`].
#[derive(Debug, Clone, Serialize)]
pub struct Written {
    /// The file.
    pub path: PathBuf,
    /// Its label.
    pub label: f64,
    /// Its repetition number.
    pub repetition: u32,
    /// Rows written.
    pub rows: usize,
}

/// One simulated recording of [`simulate`], not yet written anywhere.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// Its file stem, `<stem>_complete_<r>` as the authors named theirs.
    pub name: String,
    /// Its label.
    pub label: f64,
    /// Its repetition number.
    pub repetition: u32,
    /// The recording.
    pub recording: Recording,
}

/// The random draws of one recording of [`simulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordingDraws {
    /// The surface, an index into [`ExperimentConfig::surfaces`].
    pub surface: usize,
    /// The repetition number (1 to [`ExperimentConfig::recordings`]).
    pub repetition: u32,
    /// Where the stroke starts before the feature's near edge, mm.
    pub start_mm: f64,
    /// The line across the plate, mm.
    pub line_y: f64,
    /// Where the stroke starts in the haptic device's frame, mm.
    pub position_offset_mm: f64,
    /// Seed of the recording's noise and roughness.
    pub seed: u64,
}

/// Every recording's draws from the experiment's seed, in the order [`simulate`] makes the
/// recordings (surface by surface, repetition by repetition).
pub fn recording_draws(config: &ExperimentConfig) -> Vec<RecordingDraws> {
    let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
    let mut out = Vec::new();
    for surface in 0..config.surfaces().len() {
        for repetition in 1..=config.recordings {
            let (lo, hi) = config.start_range_mm;
            let start_mm = if hi > lo {
                rng.random_range(lo..hi)
            } else {
                lo
            };
            // Lines cross the bump's top (±1 mm) as the authors' slides did.
            let line_y = 50.0 + rng.random_range(-1.0..1.0);
            // The haptic device's frame: the stroke starts somewhere 8–14 mm from its origin.
            let position_offset_mm = rng.random_range(8.0..14.0);
            let seed = rng.random::<u64>();
            out.push(RecordingDraws {
                surface,
                repetition,
                start_mm,
                line_y,
                position_offset_mm,
                seed,
            });
        }
    }
    out
}

/// [`simulate_recording`] of the recording with draws `d`.
pub fn simulate_drawn(
    config: &ExperimentConfig,
    surfaces: &[(String, f64, Surface, f64)],
    d: &RecordingDraws,
) -> Result<Recording, SimError> {
    let (_, label, surface, edge_x) = &surfaces[d.surface];
    simulate_recording(
        config,
        surface,
        config.mount(d.surface),
        *label,
        d.repetition,
        *edge_x,
        d.start_mm,
        d.line_y,
        d.position_offset_mm,
        d.seed,
    )
}

/// Simulates every recording of the experiment in memory, in the order and with the draws
/// [`generate`] writes them ([`recording_draws`]), calling `progress(done, total)` after each
/// recording.
pub fn simulate(
    config: &ExperimentConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<Simulated>, SimError> {
    config.validate()?;
    let surfaces = config.surfaces();
    let draws = recording_draws(config);
    let mut out = Vec::with_capacity(draws.len());
    for d in &draws {
        let (stem, label, _, _) = &surfaces[d.surface];
        let recording = simulate_drawn(config, &surfaces, d)?;
        out.push(Simulated {
            name: format!("{stem}_complete_{}", d.repetition),
            label: *label,
            repetition: d.repetition,
            recording,
        });
        progress(out.len(), draws.len());
    }
    Ok(out)
}

/// [`simulate`], each recording paired with the name the tactile training facts list for it,
/// `sim-seed<S>-<stem>_complete_<r>` (`S` the experiment's seed): simulated recordings to train
/// or test the tactile models on beside the authors' files.
pub fn simulate_named(
    config: &ExperimentConfig,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<(PathBuf, Recording)>, SimError> {
    Ok(simulate(config, progress)?
        .into_iter()
        .map(|s| {
            let name = format!("sim-seed{}-{}", config.seed, s.name);
            (PathBuf::from(name), s.recording)
        })
        .collect())
}

/// Generates every recording of the experiment into `out` (created if needed) as
/// `<stem>_complete_<r>.<ext>` with `ext` "csv" or "mat", calling `progress(done, total)` after
/// each recording is simulated.
pub fn generate(
    config: &ExperimentConfig,
    out: &Path,
    ext: &str,
    progress: impl FnMut(usize, usize),
) -> Result<Vec<Written>, SimError> {
    config.validate()?;
    std::fs::create_dir_all(out).map_err(SimError::io(out))?;
    let simulated = simulate(config, progress)?;
    let mut written = Vec::with_capacity(simulated.len());
    for s in simulated {
        let path = out.join(format!("{}.{ext}", s.name));
        write_recording(&path, &s.recording)?;
        written.push(Written {
            path,
            label: s.label,
            repetition: s.repetition,
            rows: s.recording.rows.len(),
        });
    }
    Ok(written)
}

/// What [`generate_dataset`] wrote and how fast.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetReport {
    /// The output folder.
    pub out: PathBuf,
    /// The files written.
    pub files: Vec<Written>,
    /// Recordings written.
    pub recordings: usize,
    /// Rows written, over all recordings.
    pub rows: usize,
    /// Simulated time, s (rows at the sensor's sampling rate).
    pub simulated_s: f64,
    /// Wall-clock time of the simulation, s.
    pub wall_s: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
}

/// [`generate`], timed: every recording of the experiment into `out`, with the totals.
pub fn generate_dataset(
    config: &ExperimentConfig,
    out: &Path,
    ext: &str,
    progress: impl FnMut(usize, usize),
) -> Result<DatasetReport, SimError> {
    let start = std::time::Instant::now();
    let files = generate(config, out, ext, progress)?;
    let wall_s = start.elapsed().as_secs_f64();
    let rows: usize = files.iter().map(|w| w.rows).sum();
    let simulated_s = rows as f64 / SAMPLE_RATE_HZ;
    Ok(DatasetReport {
        out: out.to_path_buf(),
        recordings: files.len(),
        files,
        rows,
        simulated_s,
        wall_s,
        real_time_factor: simulated_s / wall_s.max(1e-9),
    })
}
