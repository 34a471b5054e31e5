//! The paper's plates and how they sit under the sensor: which experiment, the samples'
//! geometry, each plate's mount, and the values that `crackbot sim calibrate` fitted for them on
//! the authors' recordings (the defaults of every simulated experiment).
//!
//! Both [`experiment`](crate::experiment) (which simulates the plates) and
//! [`calibrate`](crate::calibrate) (which fits them) build on this module; neither depends on the
//! other's constants.

use serde::{Deserialize, Serialize};

use crate::SensorParams;

/// Which of the paper's experiments: the one definition in `crackbot-recording` (labels, class
/// names), re-exported here.
pub use crackbot_recording::Experiment;

/// The geometry of the paper's samples, as simulated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Samples {
    /// Depth of the cracks, mm.
    pub crack_depth_mm: f64,
    /// Angle of the cracks' walls from the plate, degrees.
    pub crack_wall_angle_deg: f64,
    /// Width of the crack of the recognition experiment, mm.
    pub recognition_crack_width_mm: f64,
    /// Widths of the width experiment, mm.
    pub widths_mm: Vec<f64>,
    /// Base radius of the bump, mm.
    pub bump_radius_mm: f64,
    /// Height of the bump, mm.
    pub bump_height_mm: f64,
    /// Amplitude of the wavy pattern, mm (the paper: 1 mm).
    pub wave_amplitude_mm: f64,
    /// Period of the wavy pattern, mm (the paper: 5 mm).
    pub wave_period_mm: f64,
    /// Roughness of the printed plates: standard deviation of the height texture, mm.
    pub roughness_rms_mm: f64,
    /// Roughness: length of its features, mm.
    pub roughness_correlation_mm: f64,
}

impl Default for Samples {
    fn default() -> Self {
        Samples {
            crack_depth_mm: 5.0,
            crack_wall_angle_deg: 85.0,
            recognition_crack_width_mm: 5.0,
            widths_mm: vec![0.0, 1.0, 2.0, 5.0, 8.0, 10.0],
            bump_radius_mm: 4.0,
            bump_height_mm: 2.0,
            wave_amplitude_mm: 1.0,
            wave_period_mm: 5.0,
            roughness_rms_mm: 0.0,
            roughness_correlation_mm: 0.5,
        }
    }
}

/// How one plate sits under the sensor in the real set-up, as far as the signals show it: its
/// colour (the proximity fibre's reflectivity) and the shift of the deformation channels' resting
/// levels that its mounting and the session's cable routing cause (the paper found that the
/// fibre cables' position shifts the data). Fitted per plate (`calibrate::fit_mounts`), not
/// modelled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateMount {
    /// Offset of D1, D2, D3, counts.
    pub offset_counts: [f64; 3],
    /// Reflectivity of the plate relative to the calibration plate.
    pub reflectivity: f64,
}

impl Default for PlateMount {
    fn default() -> Self {
        PlateMount {
            offset_counts: [0.0; 3],
            reflectivity: 1.0,
        }
    }
}

/// The sensor as calibrated against repetition 1 of the authors' recognition recordings
/// (`crackbot sim calibrate --real ../shared/data/tactile/type --repetition 1`).
pub fn calibrated_sensor() -> SensorParams {
    // The calibrated values are the defaults (see `OpticsParams::default`).
    SensorParams::default()
}

/// The plates' geometry chosen by the same calibration from `calibrate::GEOMETRY_GRID` (the paper gives
/// only the crack widths and the wave).
pub fn calibrated_samples() -> Samples {
    Samples {
        crack_depth_mm: 8.0,
        bump_radius_mm: 6.0,
        bump_height_mm: 1.0,
        // `fit_roughness` on the flat plate, repetition 1.
        roughness_rms_mm: 0.0087,
        ..Samples::default()
    }
}

/// How the paper's plates sit under the sensor, fitted on repetition 1 of the authors'
/// recordings (`crackbot sim calibrate`), in the order of the experiment's surfaces
/// (`ExperimentConfig::surfaces`).
pub fn calibrated_mounts(experiment: Experiment) -> Vec<PlateMount> {
    let table: &[([f64; 3], f64)] = match experiment {
        // Flat, crack, bump, wavy.
        Experiment::Recognition => &[
            ([-1.06, -4.99, -5.88], 0.9896),
            ([-0.14, 0.01, 1.18], 0.9958),
            ([8.30, 3.51, 1.49], 1.0051),
            ([2.82, 1.56, 2.47], 0.9939),
        ],
        // 0, 1, 2, 5, 8, 10 mm (another session: the cables sat differently).
        Experiment::Width => &[
            ([8.94, 7.01, 6.12], 1.0051),
            ([8.88, 8.01, 6.16], 0.9927),
            ([8.87, 2.01, 0.19], 1.0112),
            ([8.86, 8.01, 7.18], 1.0112),
            ([8.03, 8.14, 8.89], 1.0020),
            ([6.31, 7.49, 10.97], 0.9649),
        ],
    };
    table
        .iter()
        .map(|&(offset_counts, reflectivity)| PlateMount {
            offset_counts,
            reflectivity,
        })
        .collect()
}
