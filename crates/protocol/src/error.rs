//! Why bytes on the wire were not a frame ([`DecodeError`]).

use core::fmt;

use crate::COBS_LEN;

/// Why a chunk of bytes between two delimiters was not a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DecodeError {
    /// The CRC-32C in the frame does not match its contents (bit flips on the line).
    Crc {
        /// CRC carried by the frame.
        expected: u32,
        /// CRC computed over the received bytes.
        actual: u32,
    },
    /// The chunk is not valid COBS.
    Cobs,
    /// The chunk is shorter than a frame (bytes lost, or a corrupted byte became a delimiter).
    Truncated {
        /// Bytes received between the delimiters.
        len: usize,
    },
    /// More bytes than a frame arrived without a delimiter (garbage, or a lost delimiter); they
    /// were discarded.
    Overlong {
        /// Bytes discarded before the next delimiter.
        len: usize,
    },
    /// The frame carries a protocol version this decoder does not speak.
    UnsupportedVersion {
        /// Version byte received.
        version: u8,
    },
    /// The frame sets flag bits that this protocol version does not define.
    ReservedFlags {
        /// Flags byte received.
        flags: u8,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DecodeError::Crc { expected, actual } => {
                write!(
                    f,
                    "CRC mismatch: frame says {expected:#010x}, bytes give {actual:#010x}"
                )
            }
            DecodeError::Cobs => write!(f, "invalid COBS encoding"),
            DecodeError::Truncated { len } => {
                write!(
                    f,
                    "truncated frame: {len} bytes between delimiters, expected {COBS_LEN}"
                )
            }
            DecodeError::Overlong { len } => {
                write!(f, "{len} bytes without a delimiter (longer than a {COBS_LEN}-byte frame), discarded")
            }
            DecodeError::UnsupportedVersion { version } => write!(
                f,
                "unsupported protocol version {version} (this host speaks version {})",
                crate::PROTOCOL_VERSION
            ),
            DecodeError::ReservedFlags { flags } => {
                write!(f, "reserved flag bits set: {flags:#04x}")
            }
        }
    }
}

// `core::error::Error` is stable since Rust 1.81; the AVR board image is compiled by rustc 1.63
// (firmware/mega2560), where it does not exist yet.
#[cfg(not(target_arch = "avr"))]
impl core::error::Error for DecodeError {}
