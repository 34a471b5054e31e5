//! A mission as an [MCAP](https://mcap.dev) log that robotics tools open: Foxglove, PlotJuggler,
//! the `mcap` CLI and its Python reader. Not `ros2 bag`: rosbag2 plays only CDR-encoded ROS 2
//! messages, and these channels are Foxglove protobuf and JSON; `crackbot-rosbag` (`crackbot log
//! to-ros2`) turns a log into the bag `ros2 bag play` plays.
//!
//! * **Writing** ([`LogWriter`]): each channel has its schema in the file — the Foxglove
//!   well-known schemas where one fits (`foxglove.CompressedImage` for the camera frame,
//!   `foxglove.ImageAnnotations` for the detections and their centre lines,
//!   `foxglove.SceneUpdate` for the plan, `foxglove.FrameTransform` for the arm's pose,
//!   `foxglove.Log` for the log), JSON with a JSON Schema for the rest (the four tactile
//!   channels at 400 Hz with the finger's position along the stroke, the arm's pose in surface
//!   mm, verdicts, stream health, the mission's stage and its report). Every message is stamped
//!   with the host's synchronised clock as Unix nanoseconds, so a viewer's plots line up with the
//!   arm. Chunked, zstd-compressed, with a summary and message indexes, so a viewer seeks.
//! * **Reading** ([`read_log`]): every message back, decoded, for replays. A truncated or
//!   corrupt file is a [`LogError`] that says which, never a panic.
//! * **Live** (cargo feature `live`, [`LogWriter::serve`]): the same channels over the Foxglove
//!   WebSocket protocol, so the Foxglove app watches a mission as it runs.
//!
//! The crate knows nothing of missions: `crackbot-mission` turns its progress into these
//! messages, and the front ends turn what [`read_log`] returns into their own types.

#[cfg(feature = "live")]
mod live;
mod reader;
mod topics;
mod writer;

#[cfg(feature = "live")]
pub use live::DEFAULT_LIVE_ADDR;
pub use reader::{read_log, tactile_rows, LoggedMessage, MissionLog, Payload, TactileRow};
pub use topics::{JsonTopic, Topic};
pub use writer::{Label, LogLevel, LogWriter, Polyline, SampleMessage, SceneLine};

use std::path::PathBuf;

/// What went wrong with a mission log.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LogError {
    /// The file could not be created, written or read.
    #[error("{path}: {source}")]
    Io {
        /// The log file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The Foxglove SDK refused (a channel, the MCAP sink or the live server).
    #[error("{what}: {detail}")]
    Sdk {
        /// What was being done.
        what: &'static str,
        /// The SDK's message.
        detail: String,
    },
    /// A message could not be encoded as JSON (a value JSON cannot hold).
    #[error("the {topic} message could not be encoded: {source}")]
    Encode {
        /// The channel.
        topic: &'static str,
        /// Why.
        source: serde_json::Error,
    },
    /// The file is not a whole MCAP file (cut short, or not MCAP at all).
    #[error("{path}: not a complete MCAP file ({detail})")]
    Corrupt {
        /// The log file.
        path: PathBuf,
        /// What the reader found.
        detail: String,
    },
    /// A message in the file does not decode as its channel's schema says.
    #[error("{path}: message {index} on {topic} does not decode: {detail}")]
    BadMessage {
        /// The log file.
        path: PathBuf,
        /// Its channel's topic.
        topic: String,
        /// Its place in the file, from 0.
        index: usize,
        /// Why.
        detail: String,
    },
    /// The live server could not start (feature `live`).
    #[error("the Foxglove live server on {addr}: {detail}")]
    Serve {
        /// Where it was to listen.
        addr: String,
        /// Why.
        detail: String,
    },
}

/// Nanoseconds since the Unix epoch of `t`, saturating.
pub fn unix_ns(t: std::time::SystemTime) -> u64 {
    t.duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
}
