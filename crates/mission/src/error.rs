//! The errors of a mission: one enum, each variant naming what failed and keeping the error it
//! came from (`#[source]`), so a front end can print the whole chain.

use std::path::Path;

/// Errors of a mission.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MissionError {
    /// A mission asked for from outside (a station's start request over telemetry) cannot be
    /// run as asked.
    #[error("the start request's {field} cannot be used: {reason}")]
    StartRequest {
        /// The request's field (`mode`, `scene_toml`).
        field: &'static str,
        /// Why.
        reason: String,
    },
    /// A file or folder could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// Which.
        path: std::path::PathBuf,
        /// What went wrong.
        #[source]
        source: std::io::Error,
    },
    /// The mission's log (`mission.mcap`) could not be written.
    #[error("the mission log: {0}")]
    Log(#[from] crackbot_mcap::LogError),
    /// A mission on hardware lacks an input it needs.
    #[error("a {mode} mission needs {what}")]
    Missing {
        /// The mission's mode.
        mode: &'static str,
        /// What, and the flag that gives it.
        what: &'static str,
    },
    /// The camera gave no frame.
    #[error("camera: {0}")]
    Camera(#[from] crackbot_vision::camera::CameraError),
    /// The camera's pixel → surface mapping cannot be inverted.
    #[error("the camera's homography is singular")]
    SingularHomography,
    /// The camera frame could not be saved.
    #[error("{}: {source}", path.display())]
    Image {
        /// Where.
        path: std::path::PathBuf,
        /// What went wrong.
        #[source]
        source: image::ImageError,
    },
    /// The report could not be written as JSON.
    #[error("the report: {0}")]
    Report(#[from] serde_json::Error),
    /// A deployed model lacks a class the mission needs.
    #[error("the recognition model has no `{class}` class")]
    MissingClass {
        /// The class.
        class: &'static str,
    },
    /// A mission setting is out of range.
    #[error("the setting {field} = {value} is outside {allowed}")]
    Setting {
        /// The setting's key in the configuration file (`section.key`; a site file's own key for
        /// the site's fields).
        field: &'static str,
        /// The value given.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// The sensor link failed.
    #[error(transparent)]
    Acquisition(#[from] crackbot_acquisition::AcquisitionError),
    /// The emulated sensor failed.
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Emulator(#[from] crackbot_emulator::EmulatorError),
    /// The simulator could not be set up.
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Sim(#[from] crackbot_sim::SimError),
    /// A site file could not be parsed.
    #[error("the site file {}: {}", path.display(), source.message())]
    SiteFile {
        /// The file.
        path: std::path::PathBuf,
        /// What the TOML parser said (boxed: it is large, and this is the rare path).
        #[source]
        source: Box<toml::de::Error>,
    },
    /// A mission configuration file could not be read as one.
    #[error("the configuration file {}: {}", path.display(), config_file_text(key.as_deref(), source))]
    ConfigFile {
        /// The file.
        path: std::path::PathBuf,
        /// The key the error is about (`print_check.height_mm`), where the file parsed as TOML.
        key: Option<String>,
        /// What the TOML reader said (boxed: it is large, and this is the rare path).
        #[source]
        source: Box<toml::de::Error>,
    },
    /// A configuration could not be written as TOML.
    #[error("the configuration as TOML: {source}")]
    ConfigWrite {
        /// What the TOML writer said.
        #[source]
        source: Box<toml::ser::Error>,
    },
    /// The site's proximity fibre is out of range.
    #[error(transparent)]
    Fibre(#[from] crackbot_fibre::FibreError),
    /// A camera calibration file is unusable or does not fit the frame.
    #[error(transparent)]
    CameraCalibration(#[from] crackbot_calib::FileError),
    /// A calibration file is unusable.
    #[error(transparent)]
    Calibration(#[from] crackbot_acquisition::calibration::CalibrationError),
    /// Nothing arrived from the sensor.
    #[error("no sample arrived over {port}")]
    NoSamples {
        /// The serial device that stayed silent.
        port: String,
    },
    /// The sensor's port went away mid-mission.
    #[error("the sensor's port {port} vanished")]
    SensorLost {
        /// The device.
        port: String,
    },
    /// The sensor stream stopped mid-slide (retried once).
    #[error("the sensor stream over {port} stalled mid-slide ({detail})")]
    SensorStalled {
        /// The device.
        port: String,
        /// What showed it.
        detail: String,
    },
    /// The controller does not answer.
    #[error("the manipulator controller at {addr} is unreachable (no state for 2 s or no acknowledgement): the arm was told to stop")]
    ControllerUnreachable {
        /// Its address.
        addr: String,
    },
    /// The controller restarted mid-slide (retried once).
    #[error("the manipulator controller restarted mid-slide")]
    ControllerRestarted,
    /// The controller refused a command.
    #[error("the controller refused {what}: {reason}")]
    Refused {
        /// Which command.
        what: String,
        /// Its reason.
        reason: String,
    },
    /// Something took far longer than planned.
    #[error("{what} did not finish within {seconds:.1} s: the arm was told to stop")]
    Timeout {
        /// What.
        what: String,
        /// The budget, s.
        seconds: f64,
    },
    /// The link to the controller failed: `what` the mission was doing.
    #[error("link: {what}: {source}")]
    Link {
        /// What the mission was doing (`binding 0.0.0.0:7701`, `the link key`, `talking to the
        /// controller`).
        what: String,
        /// The link's own error.
        #[source]
        source: crackbot_link::LinkError,
    },
    /// The simulated rig's fresh link key was refused.
    #[error("link: the simulated rig's key: {source}")]
    LinkKey {
        /// Why.
        #[source]
        source: crackbot_link::KeyError,
    },
    /// Stopped by the operator (the arm was stopped first).
    #[error("interrupted: the arm was stopped")]
    Interrupted,
    /// A tactile model failed to load or classify.
    #[error(transparent)]
    Tactile(#[from] crackbot_tactile::TactileError),
    /// Planning failed.
    #[error(transparent)]
    Plan(#[from] crackbot_planner::PlanError),
    /// Detection failed.
    #[error(transparent)]
    Vision(#[from] crackbot_vision::VisionError),
    /// The simulated controller failed.
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Controller(#[from] crackbot_controller::ControllerError),
}

/// What a configuration file's error says: the key and the reader's message, or where the file
/// is not TOML.
fn config_file_text(key: Option<&str>, source: &toml::de::Error) -> String {
    match key {
        Some(k) => format!("{k}: {}", source.message()),
        None => source.to_string(),
    }
}

/// The link's error `source` while the mission was doing `what`.
pub(crate) fn link_err(
    what: impl Into<String>,
    source: impl Into<crackbot_link::LinkError>,
) -> MissionError {
    MissionError::Link {
        what: what.into(),
        source: source.into(),
    }
}

/// An I/O error on `path`, naming it.
pub(crate) fn io_err(path: &Path, e: std::io::Error) -> MissionError {
    MissionError::Io {
        path: path.to_path_buf(),
        source: e,
    }
}
