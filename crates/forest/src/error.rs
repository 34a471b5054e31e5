//! Error types of the crate.

use std::path::PathBuf;

/// Everything that can go wrong in this crate. No public function panics on bad input; it returns one of
/// these instead.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ForestError {
    /// A data set or an input row is malformed (lengths, counts).
    #[error("invalid data: {0}")]
    InvalidData(String),
    /// A feature or target value is NaN or infinite.
    #[error("non-finite value {value} at row {row}, column {column}")]
    NonFinite {
        /// Row of the offending value.
        row: usize,
        /// Column (feature index) of the offending value; for a target, the number of features.
        column: usize,
        /// The value itself.
        value: f32,
    },
    /// A hyper-parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// A prediction input has the wrong shape.
    #[error("shape mismatch: {0}")]
    Shape(String),
    /// The rayon thread pool could not be built.
    #[error("thread pool: {0}")]
    ThreadPool(String),
    /// A model file could not be read, written or decoded.
    #[error("model file {}: {source}", path.display())]
    ModelFile {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: FormatError,
    },
    /// A model in memory could not be decoded (same causes as [`ForestError::ModelFile`], without a path).
    #[error("model bytes: {0}")]
    Format(#[from] FormatError),
    /// A scikit-learn JSON export could not be imported.
    #[error("scikit-learn import{}: {message}", path.as_ref().map(|p| format!(" from {}", p.display())).unwrap_or_default())]
    SklearnImport {
        /// The JSON file, when imported from a file.
        path: Option<PathBuf>,
        /// What went wrong.
        message: String,
    },
}

/// Why a serialised model was rejected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    /// Reading or writing failed.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
    /// The file does not start with the model magic number.
    #[error(
        "not a crackbot forest model (wrong magic number {found:02x?}, expected {expected:02x?})"
    )]
    BadMagic {
        /// The first bytes found.
        found: Vec<u8>,
        /// The magic number expected.
        expected: [u8; 8],
    },
    /// The format version is not one this build reads.
    #[error("unsupported format version {found} (supported: {supported:?})")]
    UnsupportedVersion {
        /// Version found in the file.
        found: u32,
        /// Versions this build can read.
        supported: &'static [u32],
    },
    /// The model is of another kind than requested (classifier vs regressor).
    #[error("model kind {found} found, expected {expected}")]
    WrongKind {
        /// Kind found in the file.
        found: &'static str,
        /// Kind that was asked for.
        expected: &'static str,
    },
    /// The file is shorter than its header says.
    #[error("truncated: {actual} bytes, header requires {expected}")]
    Truncated {
        /// Bytes required.
        expected: u64,
        /// Bytes present.
        actual: u64,
    },
    /// The file is longer than its header says.
    #[error("{extra} unexpected trailing bytes")]
    TrailingBytes {
        /// Surplus byte count.
        extra: u64,
    },
    /// The CRC-32 stored at the end does not match the contents.
    #[error("checksum mismatch: stored {stored:#010x}, computed {computed:#010x}")]
    ChecksumMismatch {
        /// CRC stored in the file.
        stored: u32,
        /// CRC computed over the contents.
        computed: u32,
    },
    /// The arrays are inconsistent (bad child, feature or leaf index, bad counts, non-finite value).
    #[error("inconsistent model: {0}")]
    Inconsistent(String),
}

/// Result alias of this crate.
pub type Result<T, E = ForestError> = std::result::Result<T, E>;
