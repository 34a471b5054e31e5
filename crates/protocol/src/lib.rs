//! The crackbot sensor wire format: the one definition of a sensor frame, shared by the firmware
//! (`crackbot-firmware`) and the host (`crackbot-acquisition`).
//!
//! `no_std`, no allocation, no panics on any input.
//!
//! # Frame
//! A frame is one 400 Hz sample of the fibre-optic finger: the three deformation channels D1, D2,
//! D3 and the proximity channel P, as raw ADC counts, with a wrapping sequence number, a wrapping
//! device timestamp in microseconds and status flags.
//!
//! # Payload layout (little-endian, [`PAYLOAD_LEN`] = 20 bytes)
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 1 | protocol version ([`PROTOCOL_VERSION`]) |
//! | 1 | 1 | [`Flags`]: bit 0–3 saturation of D1, D2, D3, P; bit 4 sample overrun |
//! | 2 | 2 | sequence number (wraps at 65 536) |
//! | 4 | 4 | device timestamp, µs (wraps after ~71.6 min) |
//! | 8 | 8 | channels D1, D2, D3, P, `u16` each |
//! | 16 | 4 | CRC-32C (Castagnoli) of bytes 0..16 |
//!
//! # Wire
//! The payload is COBS-encoded (always [`COBS_LEN`] = 21 bytes for a 20-byte payload) and sent
//! between two `0x00` delimiters: `00 <21 COBS bytes> 00`, [`WIRE_LEN`] = 23 bytes. The leading
//! delimiter makes every frame independent of its predecessor: when the trailing delimiter of one
//! frame is corrupted, the next frame still starts cleanly, so the decoder is back in sync within
//! one frame after any corruption. Empty chunks between two delimiters are ignored.
//!
//! CRC-32C makes a corrupted frame that still passes the check a 1-in-4-billion event (CRC-16
//! would let about one corrupted frame in 65 536 through, i.e. several per hour at 400 Hz under
//! heavy noise).
//!
//! # Decoding
//! [`Decoder`] takes bytes in chunks of any size and reports each frame or error through a
//! callback; it keeps counters ([`DecoderStats`]). See its docs for the resync rules.
#![no_std]

mod decoder;
mod error;
mod frame;

pub use decoder::{Decoder, DecoderStats};
pub use error::DecodeError;
pub use frame::{Channel, Flags, Frame, CHANNELS};

/// Protocol version carried in every frame; frames of other versions are rejected.
pub const PROTOCOL_VERSION: u8 = 1;
/// Bytes of a frame payload including its CRC.
pub const PAYLOAD_LEN: usize = 20;
/// Bytes of the payload covered by the CRC.
pub const CRC_COVERED_LEN: usize = 16;
/// Bytes of a COBS-encoded payload (fixed: a 20-byte payload always encodes to 21 bytes).
pub const COBS_LEN: usize = PAYLOAD_LEN + 1;
/// Bytes of one frame on the wire: delimiter, COBS bytes, delimiter.
pub const WIRE_LEN: usize = COBS_LEN + 2;
/// Frame delimiter.
pub const DELIMITER: u8 = 0x00;
/// Sample rate of the sensor, frames per second.
pub const SAMPLE_RATE_HZ: u32 = 400;
/// Period between frames in microseconds at [`SAMPLE_RATE_HZ`].
pub const SAMPLE_PERIOD_US: u32 = 1_000_000 / SAMPLE_RATE_HZ;

/// CRC-32C (iSCSI / Castagnoli), slice-by-16 tables (16 KiB).
#[cfg(not(target_pointer_width = "16"))]
const CRC32C: crc::Crc<u32, crc::Table<16>> =
    crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISCSI);
/// CRC-32C with one 1 KiB table on 16-bit microcontrollers (the ATmega2560 has 8 KiB of RAM, and
/// AVR keeps constant tables in RAM).
#[cfg(target_pointer_width = "16")]
const CRC32C: crc::Crc<u32, crc::Table<1>> =
    crc::Crc::<u32, crc::Table<1>>::new(&crc::CRC_32_ISCSI);

/// CRC-32C of `bytes` (check value of `b"123456789"` is `0xE306_9283`).
pub fn crc32c(bytes: &[u8]) -> u32 {
    CRC32C.checksum(bytes)
}

/// Minimum UART baud rate that carries `rate_hz` frames per second with 8N1 framing
/// (10 bits per byte on the line).
pub const fn min_baud_for_rate(rate_hz: u32) -> u32 {
    rate_hz * WIRE_LEN as u32 * 10
}

/// The checked-in golden vectors (`golden/frames.json`, written by `golden/generate.py`, an
/// independent Python implementation of this format). Read by the tests of this crate, of the
/// firmware and of the host, so the two sides of the link can never drift apart.
pub const GOLDEN_VECTORS_JSON: &str = include_str!("../golden/frames.json");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32c_check_value() {
        assert_eq!(crc32c(b"123456789"), 0xE306_9283);
    }

    #[test]
    fn baud_budget_at_400_hz() {
        assert_eq!(min_baud_for_rate(400), 92_000);
        assert!(min_baud_for_rate(400) < 115_200);
        assert!(min_baud_for_rate(400) > 57_600);
    }
}
