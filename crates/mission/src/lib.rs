//! The mission library: what an operator runs, as one API that every front end calls.
//!
//! The `crackbot` command line, the headless robot binary and the operator app hold no logic of
//! their own: they turn their inputs (flags, a config file, buttons) into the configurations of
//! this crate, call it, and display the typed, `Serialize` reports it returns. Progress and live
//! data reach them through callbacks; stopping goes in as a future.
//!
//! Today:
//! * [`demo`]: the acquisition demo on a simulated scene: the simulated finger slides across a
//!   crack, the real sensor firmware samples it on this host and streams 400 Hz frames into a new
//!   pseudo-terminal, the acquisition reads them back over the real serial path, records them to
//!   CSV and summarises the stream.
//!
//! Recording a real sensor and replaying recordings are sessions of `crackbot-acquisition`
//! ([`crackbot_acquisition::RecordSession`], [`crackbot_acquisition::session::summarise_replay`]);
//! detection in camera frames is `crackbot-vision`'s.

pub mod demo;
pub mod sync;

pub use demo::{run_demo, DemoConfig, DemoReport, DemoSurface};

/// Errors of a mission.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MissionError {
    /// A setting is out of range; the message names it.
    #[error("{0}")]
    Invalid(String),
    /// The sensor link failed.
    #[error(transparent)]
    Acquisition(#[from] crackbot_acquisition::AcquisitionError),
    /// The emulated sensor failed.
    #[error(transparent)]
    Emulator(#[from] crackbot_emulator::EmulatorError),
    /// The simulator could not be set up.
    #[error(transparent)]
    Sim(#[from] crackbot_sim::SimError),
    /// A calibration file is unusable.
    #[error(transparent)]
    Calibration(#[from] crackbot_acquisition::calibration::CalibrationError),
    /// Nothing arrived from the sensor.
    #[error("no sample arrived over {port}")]
    NoSamples {
        /// The serial device that stayed silent.
        port: String,
    },
}
