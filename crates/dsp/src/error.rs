//! The crate's error type.

use crate::Channel;

/// Everything that can go wrong in this crate. No function of the crate panics on bad input; it returns one of
/// these instead.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum DspError {
    /// A sample holds NaN or ±∞.
    #[error("sample {index}, channel {channel}: non-finite value {value}")]
    NonFinite {
        /// 0-based index of the sample in the input (batch) or in the accepted stream (streaming).
        index: usize,
        /// The offending channel (the first one, in the order D1, D2, D3, P).
        channel: Channel,
        /// The value found.
        value: f64,
    },
    /// A sample's magnitude exceeds `f32::MAX` (≈ 3.4e38): its features could not be stored as `f32`.
    #[error(
        "sample {index}, channel {channel}: value {value} is out of the f32 range of the features"
    )]
    OutOfRange {
        /// 0-based index of the sample in the input (batch) or in the accepted stream (streaming).
        index: usize,
        /// The offending channel (the first one, in the order D1, D2, D3, P).
        channel: Channel,
        /// The value found.
        value: f64,
    },
    /// The signal is too short for the operation.
    #[error("signal of {len} samples is too short: at least {min} needed")]
    TooShort {
        /// Number of samples given.
        len: usize,
        /// Minimum number of samples.
        min: usize,
    },
    /// A configuration value is invalid.
    #[error("invalid configuration: {field}: {reason}")]
    InvalidConfig {
        /// The configuration field.
        field: &'static str,
        /// Why it is invalid.
        reason: String,
    },
    /// A [`Segment`](crate::Segment) does not fit the signal it is applied to.
    #[error("segment of a {segment_len}-sample trial applied to {len} samples")]
    LengthMismatch {
        /// The trial length the segment was computed for.
        segment_len: usize,
        /// The number of samples given.
        len: usize,
    },
}

impl DspError {
    pub(crate) fn config(field: &'static str, reason: impl Into<String>) -> Self {
        DspError::InvalidConfig {
            field,
            reason: reason.into(),
        }
    }
}

/// Largest magnitude accepted in a sample: features are stored as `f32`.
pub(crate) const MAX_ABS: f64 = f32::MAX as f64;

/// Checks one value: finite and within the `f32` range.
#[inline]
pub(crate) fn check_value(index: usize, channel: Channel, value: f64) -> Result<(), DspError> {
    if !value.is_finite() {
        Err(DspError::NonFinite {
            index,
            channel,
            value,
        })
    } else if value.abs() > MAX_ABS {
        Err(DspError::OutOfRange {
            index,
            channel,
            value,
        })
    } else {
        Ok(())
    }
}

/// Checks the four channels of one sample, in the order D1, D2, D3, P.
#[inline]
pub fn check_sample(index: usize, sample: &[f64; 4]) -> Result<(), DspError> {
    for (channel, &value) in Channel::ALL.iter().zip(sample) {
        check_value(index, *channel, value)?;
    }
    Ok(())
}

/// Checks a one-channel signal (the proximity of a trial).
pub(crate) fn check_signal(signal: &[f64], channel: Channel) -> Result<(), DspError> {
    for (index, &value) in signal.iter().enumerate() {
        check_value(index, channel, value)?;
    }
    Ok(())
}
