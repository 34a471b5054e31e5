//! `crackbot-sim`: the world the robot acts in when there is no hardware.
//!
//! * [`surface`]: plates carrying cracks (polyline grooves), bumps, wavy patches, printed decoys
//!   and screws, as height and reflectivity maps.
//! * [`finger`]: the mechanics of the fibre-optic finger dragged over a surface profile: a
//!   spherical tip on a compliant body, a stiff penalty contact (≥ 1e5 N/m on a gram-scale tip),
//!   Coulomb friction with edge catching, and the integrators that can carry it (an implicit
//!   L-stable SDIRK, backward Euler, and adaptive explicit Dormand–Prince).
//! * [`optics`]: deformation and proximity → light → transducer voltage → 10-bit ADC counts, with
//!   saturation, noise, drift, per-recording offset/gain changes and surface reflectivity.
//! * [`plates`]: the paper's plates (geometry, mounts) and the values calibrated for them.
//! * [`experiment`]: the paper's two experiments (surface recognition, crack width) written as
//!   recordings in the authors' nine-column format, deterministic from a seed.
//! * [`scene`]: TOML scenes (plate, features, camera, manipulator, sensor) with validation and a
//!   built-in default; [`render`]: camera images of a scene with ground-truth boxes and the exact
//!   pixel↔mm homography.
//! * [`random_scene`]: random scenes (plate material, cracks, decoys, screws, relief, camera)
//!   for crack-detector data.
//! * [`calibrate`]: fitting the optical parameters to the authors' real recordings;
//!   [`recordings`]: reading folders of real or simulated recordings and choosing the slides that
//!   compare them.

pub mod calibrate;
pub mod camera;
pub mod experiment;
pub mod finger;
pub mod optics;
pub mod plates;
pub mod random_scene;
pub mod recordings;
pub mod render;
pub mod run;
pub mod scene;
/// The plate's surface (`crackbot-surface`), as the simulator's own module.
pub use crackbot_surface as surface;
pub mod work_precision;

use serde::{Deserialize, Serialize};

pub use finger::{FingerParams, Integrator};
pub use optics::OpticsParams;
pub use random_scene::{random_scene, RandomSceneParams};
pub use scene::Scene;
pub use surface::{Feature, Surface};

/// Everything about the sensor: its mechanics and its optics/electronics.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorParams {
    /// Mechanics of the finger.
    #[serde(default)]
    pub finger: FingerParams,
    /// Optics, transducers and ADC.
    #[serde(default)]
    pub optics: OpticsParams,
}

/// Errors of the simulator.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A setting, scene or parameter value is out of range.
    #[error("invalid setting {field} = {value}: it must be {allowed}")]
    Setting {
        /// The setting's path as a scene or parameter file names it, e.g. `camera.noise_sigma`,
        /// `features[2].width_mm`, `samples.printed_slots[1].nominal_mm`.
        field: String,
        /// The value given, as written (numbers, arrays).
        value: String,
        /// What it may be, e.g. `≥ 0`, `in [0, 1]`, `one of samples.widths_mm [1, 2]`.
        allowed: String,
    },
    /// An error in the scene read from `path` (a file, or e.g. `<builtin default.toml>`).
    #[error("{path}: {source}")]
    InScene {
        /// The scene's file.
        path: String,
        /// What is wrong with it.
        #[source]
        source: Box<SimError>,
    },
    /// The scene has no camera: there is nothing to render.
    #[error("scene {scene:?} has no camera: nothing to render (add a [camera] table)")]
    NoCamera {
        /// The scene's name.
        scene: String,
    },
    /// The camera sees none of the plate.
    #[error(
        "the camera does not see the plate: none of its corners, its centre or the look-at point \
         falls inside the image (check camera.principal_px and camera.focal_px)"
    )]
    CameraMissesPlate,
    /// The scene has no crack to slide across.
    #[error("scene {scene:?} has no crack to slide across")]
    NoCrack {
        /// The scene's name.
        scene: String,
    },
    /// Cracks are to be drawn but no crack photo strips are loaded.
    #[error("no crack photo strips loaded: cannot draw cracks")]
    NoCrackPhotos,
    /// An internal image buffer has the wrong size.
    #[error("{what} buffer of the wrong size")]
    Buffer {
        /// Which buffer.
        what: &'static str,
    },
    /// A plate↔image homography cannot be used (singular, or not fitted).
    #[error("homography: {message}")]
    Homography {
        /// Why.
        message: String,
    },
    /// A parameter text (`sim dataset --params`, `sim calibrate --start`) is not TOML.
    #[error("cannot parse the parameters: {message}")]
    Parameters {
        /// What the TOML parser said.
        message: String,
    },
    /// A table of a parameter text is unknown or does not hold what it must.
    #[error("parameter table [{table}]: {message}")]
    ParameterTable {
        /// The table, e.g. `sensor.finger`, `mounts.width`.
        table: String,
        /// What is wrong with it.
        message: String,
    },
    /// There are no real recordings to calibrate against.
    #[error("no real recordings to calibrate against")]
    NoRealRecordings,
    /// None of the real recordings is of a plate whose mount is to be fitted.
    #[error("no real recording of the plate labelled {label} to fit its mount to")]
    NoRealRecordingOfPlate {
        /// The plate's label (column 8 of its recordings).
        label: f64,
    },
    /// A scene file could not be parsed.
    #[error("cannot parse scene {path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What the TOML parser said.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The integrator could not take a step (Newton failed to converge even at the smallest
    /// step, or the state became non-finite).
    #[error("integration failed at t = {t:.6} s: {reason}")]
    Integration {
        /// Simulated time of the failure, s.
        t: f64,
        /// Why.
        reason: String,
    },
    /// Writing a recording failed.
    #[error(transparent)]
    Recording(#[from] crackbot_recording::RecordingError),
    /// Reading a folder of recordings failed.
    #[error("reading recordings in {dir}")]
    ReadRecordings {
        /// The folder.
        dir: String,
        /// Why.
        #[source]
        source: crackbot_recording::RecordingError,
    },
    /// A folder of recordings does not hold what is needed (no recording, none of the asked
    /// repetition), or a COCO file is malformed.
    #[error("{path}: {message}")]
    Data {
        /// The folder or file.
        path: String,
        /// What is missing.
        message: String,
    },
    /// Reading or decoding an image failed.
    #[error("image {path}: {message}")]
    Image {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
}

impl SimError {
    /// A [`SimError::Setting`]: `field` (as a scene or parameter file names it) has `value`, which
    /// is not `allowed`.
    pub fn setting(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        allowed: impl Into<String>,
    ) -> SimError {
        SimError::Setting {
            field: field.into(),
            value: value.to_string(),
            allowed: allowed.into(),
        }
    }

    /// A closure mapping an I/O error on `path` to [`SimError::Io`].
    pub fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> SimError + '_ {
        move |source| SimError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}

impl From<crackbot_imaging::ImagingError> for SimError {
    /// I/O failures as [`SimError::Io`], malformed COCO or JSON files as [`SimError::Data`], anything
    /// else (a homography that cannot be used) as [`SimError::Homography`].
    fn from(e: crackbot_imaging::ImagingError) -> Self {
        use crackbot_imaging::ImagingError as E;
        match e {
            E::Io { path, source } => SimError::Io {
                path: path.display().to_string(),
                source,
            },
            E::Coco { path, message } | E::Json { path, message } => SimError::Data {
                path: path.display().to_string(),
                message,
            },
            E::Homography(message) => SimError::Homography { message },
            other => SimError::Homography {
                message: other.to_string(),
            },
        }
    }
}

/// `values` as `[a, b, c]`, each as `Display` writes it (`[-1, 2.5]`, `[NaN, 0]`).
pub(crate) fn list<T: std::fmt::Display>(values: &[T]) -> String {
    let items: Vec<String> = values.iter().map(ToString::to_string).collect();
    format!("[{}]", items.join(", "))
}
