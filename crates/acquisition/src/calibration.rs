//! Per-sensor calibration: raw ADC counts to physical units.
//!
//! Each finger has its own calibration file, in TOML, holding a linear model
//!
//! ```text
//! physical = M · ((raw − offset) ⊙ gain)
//! ```
//!
//! where `raw`, `offset` and `gain` are 4-vectors over the channels D1, D2, D3, P ([`CHANNELS`]), `⊙` is the
//! element-wise product and `M` is a 4×4 matrix whose rows are the four physical outputs (by convention lateral
//! force left, lateral force right, normal force, proximity distance; the file names them in `outputs` and
//! `units`, free text). See `crates/acquisition/calibration/example.toml` for a commented file.
//!
//! [`Calibration::load`] reads, parses and validates a file; every error names the file and the offending field.
//! Validation rejects non-finite numbers, zero gains, offsets outside `0..=adc_max`, an empty `sensor_id` and an
//! effective linear map `M·diag(gain)` that is singular or ill-conditioned (SVD condition number above
//! [`MAX_CONDITION`]), because such a map cannot be inverted and amplifies ADC noise without bound.

use std::path::{Path, PathBuf};

use crackbot_protocol::Channel;
use nalgebra::{Matrix4, Vector4};

/// Names of the four raw channels, in vector order.
pub const CHANNELS: [&str; 4] = [
    Channel::D1.name(),
    Channel::D2.name(),
    Channel::D3.name(),
    Channel::P.name(),
];

/// The text of `calibration/example.toml`.
pub const EXAMPLE_TOML: &str = include_str!("../calibration/example.toml");

/// Full scale of the microcontroller's 10-bit ADC, the default for [`Calibration::adc_max`].
pub const DEFAULT_ADC_MAX: u16 = 1023;

/// Largest accepted condition number of the effective linear map `M·diag(gain)`.
pub const MAX_CONDITION: f64 = 1e12;

/// Condition number from which the map is called "singular" rather than "ill-conditioned" in messages: beyond
/// 1/ε the smallest singular value is indistinguishable from rounding error.
const SINGULAR_CONDITION: f64 = 1.0 / f64::EPSILON;

fn default_adc_max() -> u16 {
    DEFAULT_ADC_MAX
}

/// Calibration of one sensor: `physical = M · ((raw − offset) ⊙ gain)`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// Identifier of the sensor this calibration belongs to (non-empty).
    pub sensor_id: String,
    /// Resting ADC level of each channel (D1, D2, D3, P), subtracted from the raw counts; within `0..=adc_max`.
    pub offsets: [f64; 4],
    /// Per-channel gain applied after the offset (non-zero).
    pub gains: [f64; 4],
    /// Mixing matrix `M`, row-major: `matrix[output][channel]`.
    pub matrix: [[f64; 4]; 4],
    /// Free-text name of each output (row of `M`), e.g. "lateral force left".
    pub outputs: [String; 4],
    /// Unit of each output, e.g. "N" or "mm".
    pub units: [String; 4],
    /// Full scale of the ADC (1023 for 10 bits, the default when the file leaves it out).
    #[serde(default = "default_adc_max")]
    pub adc_max: u16,
}

/// Errors loading, saving, validating or using a [`Calibration`]. Every variant names the file (or, for a
/// calibration that lives only in memory, `<in-memory calibration "sensor_id">`).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CalibrationError {
    /// The file could not be read or written.
    #[error("calibration {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// The file is not valid TOML or does not have the calibration's fields and types.
    #[error("calibration {}: invalid TOML: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, with line and column when known.
        message: String,
    },
    /// `sensor_id` is empty (or only white space).
    #[error("calibration {}: sensor_id is empty", path.display())]
    EmptySensorId {
        /// The file.
        path: PathBuf,
    },
    /// `adc_max` is 0.
    #[error("calibration {}: adc_max must be positive, found 0", path.display())]
    InvalidAdcMax {
        /// The file.
        path: PathBuf,
    },
    /// A number is NaN or infinite.
    #[error("calibration {}: {field} = {value} is not a finite number", path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The field, e.g. `matrix[2][1]` or `gains[0]`.
        field: String,
        /// The value found.
        value: f64,
    },
    /// A gain is zero, which would erase its channel.
    #[error("calibration {}: gain of channel {channel} is zero", path.display())]
    ZeroGain {
        /// The file.
        path: PathBuf,
        /// The channel (see [`CHANNELS`]).
        channel: &'static str,
    },
    /// An offset lies outside the ADC range.
    #[error(
        "calibration {}: offset of channel {channel} is {value}, outside the ADC range 0..={adc_max}",
        path.display()
    )]
    OffsetOutOfRange {
        /// The file.
        path: PathBuf,
        /// The channel (see [`CHANNELS`]).
        channel: &'static str,
        /// The offset found.
        value: f64,
        /// The ADC full scale.
        adc_max: u16,
    },
    /// The effective map `M·diag(gain)` is singular or too ill-conditioned to trust or invert.
    #[error(
        "calibration {}: matrix·diag(gains) is {}",
        path.display(),
        describe_condition(*condition)
    )]
    Singular {
        /// The file.
        path: PathBuf,
        /// The SVD condition number (infinite when a singular value is exactly zero).
        condition: f64,
    },
}

fn describe_condition(condition: f64) -> String {
    if condition.is_finite() && condition < SINGULAR_CONDITION {
        format!("ill-conditioned (condition number {condition:e}, limit {MAX_CONDITION:e})")
    } else {
        format!("singular (condition number {condition:e})")
    }
}

impl Calibration {
    /// The identity calibration: offsets 0, gains 1, identity matrix, outputs in raw counts.
    pub fn identity(sensor_id: &str) -> Self {
        let mut matrix = [[0.0; 4]; 4];
        for (i, row) in matrix.iter_mut().enumerate() {
            row[i] = 1.0;
        }
        Self {
            sensor_id: sensor_id.to_string(),
            offsets: [0.0; 4],
            gains: [1.0; 4],
            matrix,
            outputs: CHANNELS.map(str::to_string),
            units: ["counts"; 4].map(str::to_string),
            adc_max: DEFAULT_ADC_MAX,
        }
    }

    /// Reads, parses and validates a calibration file.
    pub fn load(path: &Path) -> Result<Self, CalibrationError> {
        let text = std::fs::read_to_string(path).map_err(|source| CalibrationError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// The example calibration shipped with crackbot (`calibration/example.toml`), used when a run
    /// is given no calibration file of its own.
    pub fn example() -> Result<Self, CalibrationError> {
        Self::from_toml_str(EXAMPLE_TOML, "built-in example calibration")
    }

    /// Parses and validates a calibration from TOML text; `source_name` names it in error messages.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Self, CalibrationError> {
        Self::parse(text, Path::new(source_name))
    }

    fn parse(text: &str, path: &Path) -> Result<Self, CalibrationError> {
        let calibration: Self = toml::from_str(text).map_err(|e| CalibrationError::Parse {
            path: path.to_path_buf(),
            message: describe_toml_error(&e, text),
        })?;
        calibration.check(path)?;
        Ok(calibration)
    }

    /// Validates and writes the calibration to `path` as TOML (created or replaced). An invalid calibration is
    /// refused and nothing is written.
    pub fn save(&self, path: &Path) -> Result<(), CalibrationError> {
        self.check(path)?;
        let text = self.to_toml_text();
        std::fs::write(path, text).map_err(|source| CalibrationError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Validates the calibration (see the [module documentation](self)); errors name it as
    /// `<in-memory calibration "sensor_id">`.
    pub fn validate(&self) -> Result<(), CalibrationError> {
        self.check(&self.in_memory_name())
    }

    fn in_memory_name(&self) -> PathBuf {
        PathBuf::from(format!("<in-memory calibration {:?}>", self.sensor_id))
    }

    fn check(&self, path: &Path) -> Result<(), CalibrationError> {
        let path_buf = || path.to_path_buf();
        if self.sensor_id.trim().is_empty() {
            return Err(CalibrationError::EmptySensorId { path: path_buf() });
        }
        if self.adc_max == 0 {
            return Err(CalibrationError::InvalidAdcMax { path: path_buf() });
        }
        let non_finite = |field: String, value: f64| CalibrationError::NonFinite {
            path: path_buf(),
            field,
            value,
        };
        for (i, &value) in self.offsets.iter().enumerate() {
            if !value.is_finite() {
                return Err(non_finite(format!("offsets[{i}]"), value));
            }
        }
        for (i, &value) in self.gains.iter().enumerate() {
            if !value.is_finite() {
                return Err(non_finite(format!("gains[{i}]"), value));
            }
        }
        for (r, row) in self.matrix.iter().enumerate() {
            for (c, &value) in row.iter().enumerate() {
                if !value.is_finite() {
                    return Err(non_finite(format!("matrix[{r}][{c}]"), value));
                }
            }
        }
        for (&gain, channel) in self.gains.iter().zip(CHANNELS) {
            if gain == 0.0 {
                return Err(CalibrationError::ZeroGain {
                    path: path_buf(),
                    channel,
                });
            }
        }
        for (&value, channel) in self.offsets.iter().zip(CHANNELS) {
            if !(0.0..=f64::from(self.adc_max)).contains(&value) {
                return Err(CalibrationError::OffsetOutOfRange {
                    path: path_buf(),
                    channel,
                    value,
                    adc_max: self.adc_max,
                });
            }
        }
        let condition = self.condition_number();
        // A NaN condition number (which `condition_number` never returns) would be rejected too.
        if condition.is_nan() || condition > MAX_CONDITION {
            return Err(CalibrationError::Singular {
                path: path_buf(),
                condition,
            });
        }
        Ok(())
    }

    /// The calibration as commented TOML, one matrix row per line.
    fn to_toml_text(&self) -> String {
        use std::fmt::Write as _;
        let float = |v: f64| toml::Value::Float(v).to_string();
        let string = |s: &str| toml::Value::String(s.to_string()).to_string();
        let floats = |vs: &[f64; 4]| vs.map(float).join(", ");
        let strings =
            |vs: &[String; 4]| vs.iter().map(|s| string(s)).collect::<Vec<_>>().join(", ");
        let mut text = String::new();
        // Writing to a String cannot fail.
        let _ = writeln!(
            text,
            "# crackbot sensor calibration: physical = matrix · ((raw − offsets) ⊙ gains)\n\
             # Channels, in vector order: D1, D2, D3, P.\n\n\
             sensor_id = {}\n\
             adc_max = {}\n\n\
             # Resting ADC level of each channel (counts).\n\
             offsets = [{}]\n\
             # Per-channel gain applied after the offset.\n\
             gains = [{}]\n\
             # One row per output, one column per channel.\n\
             matrix = [",
            string(&self.sensor_id),
            self.adc_max,
            floats(&self.offsets),
            floats(&self.gains),
        );
        for (row, (output, unit)) in self.matrix.iter().zip(self.outputs.iter().zip(&self.units)) {
            let comment = format!("{output} ({unit})").replace(['\n', '\r'], " ");
            let _ = writeln!(text, "    [{}], # {comment}", floats(row));
        }
        let _ = writeln!(
            text,
            "]\noutputs = [{}]\nunits = [{}]",
            strings(&self.outputs),
            strings(&self.units)
        );
        text
    }

    fn m(&self) -> Matrix4<f64> {
        Matrix4::from_fn(|r, c| self.matrix[r][c])
    }

    /// The effective linear map `M·diag(gain)` from offset-corrected counts to physical units.
    fn effective(&self) -> Matrix4<f64> {
        Matrix4::from_fn(|r, c| self.matrix[r][c] * self.gains[c])
    }

    /// SVD condition number (largest over smallest singular value) of the effective linear map `M·diag(gain)`.
    ///
    /// Returns `f64::INFINITY` when the map is singular (smallest singular value 0) or cannot be computed (a
    /// non-finite entry, or the SVD does not converge); never NaN.
    pub fn condition_number(&self) -> f64 {
        let a = self.effective();
        if a.iter().any(|v| !v.is_finite()) {
            return f64::INFINITY;
        }
        let Some(svd) = nalgebra::SVD::try_new(a, false, false, f64::EPSILON, 10_000) else {
            return f64::INFINITY;
        };
        let s = svd.singular_values;
        let max = s.iter().copied().fold(0.0_f64, f64::max);
        let min = s.iter().copied().fold(f64::INFINITY, f64::min);
        if min.is_nan() || min <= 0.0 || !max.is_finite() {
            return f64::INFINITY;
        }
        max / min
    }

    /// Converts raw ADC counts (D1, D2, D3, P) to the four physical outputs. Does not validate; a calibration from
    /// [`load`](Self::load) or [`from_toml_str`](Self::from_toml_str) is already valid.
    pub fn apply(&self, raw: [u16; 4]) -> [f64; 4] {
        let x = Vector4::from_fn(|i, _| (f64::from(raw[i]) - self.offsets[i]) * self.gains[i]);
        let y = self.m() * x;
        [y[0], y[1], y[2], y[3]]
    }

    /// Maps physical outputs back to (fractional) raw counts, the inverse of [`apply`](Self::apply); for tests and
    /// simulation. The result is not rounded nor clamped to `0..=adc_max`.
    ///
    /// Fails when the calibration is invalid ([`validate`](Self::validate)'s errors) or a value of `physical` (field
    /// `physical[i]`) or of the result (field `raw[i]`) is not finite.
    pub fn invert(&self, physical: [f64; 4]) -> Result<[f64; 4], CalibrationError> {
        let name = self.in_memory_name();
        self.check(&name)?;
        for (i, &value) in physical.iter().enumerate() {
            if !value.is_finite() {
                return Err(CalibrationError::NonFinite {
                    path: name,
                    field: format!("physical[{i}]"),
                    value,
                });
            }
        }
        let y = Vector4::from(physical);
        let Some(scaled) = self.m().lu().solve(&y) else {
            return Err(CalibrationError::Singular {
                path: name,
                condition: f64::INFINITY,
            });
        };
        let mut raw = [0.0; 4];
        for (i, out) in raw.iter_mut().enumerate() {
            *out = scaled[i] / self.gains[i] + self.offsets[i];
            if !out.is_finite() {
                return Err(CalibrationError::NonFinite {
                    path: name,
                    field: format!("raw[{i}]"),
                    value: *out,
                });
            }
        }
        Ok(raw)
    }
}

/// The TOML error's own message, prefixed with the line and column of its span when it has one.
fn describe_toml_error(error: &toml::de::Error, text: &str) -> String {
    let message = error.message().trim_end();
    match error.span() {
        Some(span) => {
            let mut start = span.start.min(text.len());
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let before = text.get(..start).unwrap_or("");
            let line = before.matches('\n').count() + 1;
            let column = before
                .rfind('\n')
                .map_or(before, |i| &before[i + 1..])
                .chars()
                .count()
                + 1;
            format!("line {line}, column {column}: {message}")
        }
        None => message.to_string(),
    }
}
