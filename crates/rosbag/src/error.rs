//! What can go wrong turning a mission's log into a ROS 2 bag.

use std::path::PathBuf;

/// Why a bag could not be made. Every variant names what it was at.
#[derive(Debug, thiserror::Error)]
pub enum RosbagError {
    /// The mission's log could not be read.
    #[error(transparent)]
    Log(#[from] crackbot_mcap::LogError),
    /// A message of the log lacks a field its ROS 2 message needs, or holds a value of the
    /// wrong kind.
    #[error("{topic} (logged at {log_time_ns} ns): field `{field}` {problem}")]
    Field {
        /// The log's topic.
        topic: String,
        /// When it was logged.
        log_time_ns: u64,
        /// The field.
        field: &'static str,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// A message could not be encoded as CDR.
    #[error("{topic}: could not encode as CDR: {source}")]
    Cdr {
        /// The bag's topic.
        topic: &'static str,
        /// What the encoder said.
        #[source]
        source: cdr_encoding::Error,
    },
    /// The bag's folder or a file in it could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// The MCAP writer failed.
    #[error("{}: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What the writer said.
        #[source]
        source: mcap::McapError,
    },
    /// The bag's folder exists and is not empty.
    #[error("{}: already exists and is not empty (a bag is a folder of its own)", path.display())]
    Exists {
        /// The folder.
        path: PathBuf,
    },
}
