//! What can go wrong with a target, each naming what is wrong.

use std::path::PathBuf;

/// A target that cannot be used, drawn or found.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TargetError {
    /// A field of the target's description out of range.
    #[error("target: {field} = {value}: expected {expected}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: String,
        /// What it should be.
        expected: String,
    },
    /// A file that could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A target file that is not valid TOML or has unknown or missing keys.
    #[error("{}: not a target file: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What the parser said.
        message: String,
    },
    /// An image that could not be written.
    #[error(transparent)]
    Png(#[from] crackbot_imaging::scaled_png::ScaledPngError),
    /// The AprilTag detector could not be made.
    #[error("the AprilTag detector: {message}")]
    Detector {
        /// What the library said.
        message: String,
    },
}
