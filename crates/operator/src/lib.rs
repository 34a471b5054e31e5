//! The operator's desktop app (eframe/egui) for crackbot: the camera frame with the detector's
//! candidates and the planned slides drawn on it, the tactile finger's four channels (D1, D2, D3,
//! P) live at 400 Hz, the verdicts, the candidates, stream health, one tab per robot, and the
//! controls (start with a confirm step, stop, an always-visible emergency stop) and exports (CSV
//! of the visible signals, the report's JSON, a screenshot).
//!
//! Every source feeds the same model, [`crackbot_telemetry::Fleet`]: a live fleet over Zenoh
//! ([`source::Backend::live`]), a mission run in-process on the simulated scene with no network
//! ([`source::Backend::sim`]), or a saved mission ([`replay`]). The UI never waits on I/O: the
//! missions, the network, file reads and writes run on threads.
//!
//! The logic is testable without a window: [`app::OperatorApp::ui`] draws into any
//! [`egui::Ui`] (the tests drive it with `egui_kittest`), and the helpers ([`decimate`],
//! [`export`], [`overlay`], [`frames`]) are pure.

pub mod app;
pub mod decimate;
pub mod export;
pub mod frames;
pub mod overlay;
pub mod replay;
pub mod source;

pub use app::{OperatorApp, Pending};
pub use source::Backend;

use std::path::PathBuf;

/// Errors of the operator app (shown in its log, never a panic).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OperatorError {
    /// A mission was started while one is running.
    #[error("a mission is running: stop it first")]
    AlreadyRunning,
    /// The mission's thread could not be started.
    #[error("starting the mission thread: {0}")]
    Thread(std::io::Error),
    /// The mission's report is not JSON.
    #[error("the mission's report is not JSON: {0}")]
    Report(#[from] serde_json::Error),
    /// A screenshot could not be encoded.
    #[error("the screenshot: {reason}")]
    Screenshot {
        /// Why.
        reason: String,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A saved mission could not be replayed.
    #[error("replay {path}: {detail}")]
    Replay {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        detail: String,
    },
    /// The telemetry (Zenoh, commands).
    #[error(transparent)]
    Telemetry(#[from] crackbot_telemetry::TelemetryError),
}
