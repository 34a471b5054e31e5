//! Errors of the vision crate.

use std::path::PathBuf;

/// Everything that can go wrong in `crackbot-vision`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VisionError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// An image could not be decoded or encoded.
    #[error("{path}: {message}")]
    Image {
        /// The image file (empty for in-memory images).
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A COCO file is malformed or inconsistent.
    #[error("COCO file {path}: {message}")]
    Coco {
        /// The file (empty for in-memory data).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Input that cannot be used (degenerate geometry, non-finite values, bad parameters…).
    #[error("{0}")]
    Invalid(String),
    /// A homography calibration file is malformed or degenerate.
    #[error("calibration {path}: {message}")]
    Calibration {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A line of a point-pairs file (`u,v,x_mm,y_mm`) is not four numbers.
    #[error("{path} line {line}: {message}")]
    PointPairs {
        /// The file.
        path: PathBuf,
        /// The line, counted from 1.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The ONNX model or runtime could not be used.
    #[error("{0}")]
    Runtime(String),
}

impl VisionError {
    /// Maps an I/O failure on `path` (for `map_err`).
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> VisionError + '_ {
        move |source| VisionError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

impl From<crackbot_imaging::ImagingError> for VisionError {
    /// The shared COCO and homography code's errors, as the variants this crate always used
    /// for them (same messages).
    fn from(e: crackbot_imaging::ImagingError) -> Self {
        use crackbot_imaging::ImagingError as E;
        match e {
            E::Io { path, source } => VisionError::Io { path, source },
            E::Coco { path, message } => VisionError::Coco { path, message },
            E::Homography(message) => VisionError::Invalid(message),
            other => VisionError::Invalid(other.to_string()),
        }
    }
}
