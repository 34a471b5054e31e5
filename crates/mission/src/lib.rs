//! The mission library: what an operator runs, as one API that every front end calls.
//!
//! The `crackbot` command line, the headless robot binary and the operator app hold no logic of
//! their own: they turn their inputs (flags, a config file, buttons) into the configurations of
//! this crate, call it, and display the typed, `Serialize` reports it returns. Progress and live
//! data reach them through callbacks; stopping goes in as a future.
//!
//! * [`inspect`]: the inspection mission (tactile, vision or fused) over the authenticated link,
//!   on a rig ([`inspect::RigBackend`]): hardware, or with the cargo feature `sim` (on by
//!   default) the simulated controller and sensor started in-process on a simulated scene.
//! * [`sync`]: passive clock synchronisation of the sensor's and the controller's clocks.
//! * `demo` (feature `sim`): the acquisition demo on a simulated scene: the simulated finger slides across a
//!   crack, the real sensor firmware samples it on this host and streams 400 Hz frames into a new
//!   pseudo-terminal, the acquisition reads them back over the real serial path, records them to
//!   CSV and summarises the stream.
//!
//! Recording a real sensor and replaying recordings are sessions of `crackbot-acquisition`
//! ([`crackbot_acquisition::RecordSession`], [`crackbot_acquisition::session::summarise_replay`]);
//! detection in camera frames is `crackbot-vision`'s.

#[cfg(feature = "sim")]
pub mod demo;
pub mod inspect;
pub mod sync;

#[cfg(feature = "sim")]
pub use demo::{run_demo, DemoConfig, DemoReport, DemoSurface};
pub use inspect::{
    print_check_height, run_inspection, InspectConfig, InspectMode, InspectReport, Progress,
    PRINT_CHECK_HEIGHT_MM, PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_SPEED_MM_S,
};

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
        /// The setting's name in [`InspectConfig`].
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
    #[error("the site file {}: {message}", path.display())]
    SiteFile {
        /// The file.
        path: std::path::PathBuf,
        /// What the TOML parser said.
        message: String,
    },
    /// The site's proximity fibre is out of range.
    #[error(transparent)]
    Fibre(#[from] crackbot_fibre::FibreError),
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
    /// The link failed.
    #[error("link: {0}")]
    Link(String),
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
