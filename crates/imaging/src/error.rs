//! Errors of `crackbot-imaging`.

use std::path::PathBuf;

/// Everything that can go wrong in `crackbot-imaging`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImagingError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A COCO file is malformed or inconsistent.
    #[error("COCO file {path}: {message}")]
    Coco {
        /// The file (empty for in-memory data).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A JSON file of another kind (e.g. a detector set's `features.json`) is malformed.
    #[error("{path}: {message}")]
    Json {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A homography that cannot be used (not finite, singular), or a point it cannot map.
    #[error("{0}")]
    Homography(String),
}

impl ImagingError {
    /// Maps an I/O failure on `path` (for `map_err`).
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> ImagingError + '_ {
        move |source| ImagingError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
