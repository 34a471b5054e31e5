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
pub mod surface;
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
    /// A scene or parameter is invalid; the message names the field and the value.
    #[error("invalid scene: {0}")]
    Invalid(String),
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
    /// else (a homography that cannot be used) as [`SimError::Invalid`].
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
            other => SimError::Invalid(other.to_string()),
        }
    }
}
