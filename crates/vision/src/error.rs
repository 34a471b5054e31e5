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
    /// A setting is out of range (a threshold, a tolerance, a detector parameter).
    #[error("invalid setting {field} = {value}: it must be {allowed}")]
    Setting {
        /// The setting, as the config type or command-line option names it.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// Point pairs from which no homography can be fitted (too few, non-finite, duplicate or
    /// collinear points, an ill-conditioned system, a fit through infinity).
    #[error("{reason}")]
    Homography {
        /// What is degenerate, naming the side (pixel or surface) and the point.
        reason: String,
    },
    /// An input has the wrong number of values (a model's input tensor, a crack map or mask
    /// that does not fit its image).
    #[error("{what} has {got} values, expected {expected}")]
    Shape {
        /// The input.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length it must have.
        expected: usize,
    },
    /// An image with no pixels.
    #[error("image of {width}×{height} pixels: nothing to detect in")]
    EmptyImage {
        /// Width, px.
        width: u32,
        /// Height, px.
        height: u32,
    },
    /// A crack-map value that is not a probability.
    #[error("crack map value {value} is not a probability in [0, 1]")]
    NotProbability {
        /// The value.
        value: f32,
    },
    /// A value of a box head's output that cannot be (a `box_heat` value that is not a
    /// probability, a `box_reg` value that is not finite).
    #[error("box head output `{output}` value {value} at index {index} is not valid")]
    BoxHeadValue {
        /// The output's name.
        output: &'static str,
        /// The value's index, row-major.
        index: usize,
        /// The value.
        value: f32,
    },
    /// A model asked for an output it does not have (a crack map of a box model).
    #[error("{model} returns {has}, not {wanted}")]
    WrongOutput {
        /// The model's name.
        model: String,
        /// What it returns.
        has: &'static str,
        /// What was asked for.
        wanted: &'static str,
    },
    /// A features file lacks a frame the COCO file lists.
    #[error("the features file has no frame {file_name:?}")]
    MissingFrame {
        /// The frame's file name.
        file_name: String,
    },
    /// Results could not be encoded as JSON.
    #[error("cannot encode {what}: {message}")]
    Encode {
        /// What was being encoded.
        what: &'static str,
        /// The encoder's message.
        message: String,
    },
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
    /// [`VisionError::Setting`] for `field = value`, which must be `allowed`.
    pub(crate) fn setting(field: &'static str, value: f64, allowed: &'static str) -> VisionError {
        VisionError::Setting {
            field,
            value,
            allowed,
        }
    }

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
            E::Homography(reason) => VisionError::Homography { reason },
            other => VisionError::Homography {
                reason: other.to_string(),
            },
        }
    }
}

/// Refuses a crack map of `prob` or a mask of `truth` values that is not `width × height`.
pub(crate) fn check_sizes(
    prob: usize,
    truth: usize,
    width: usize,
    height: usize,
) -> Result<(), VisionError> {
    for (what, got) in [("the crack map", prob), ("the mask", truth)] {
        if got != width * height {
            return Err(VisionError::Shape {
                what,
                got,
                expected: width * height,
            });
        }
    }
    Ok(())
}
