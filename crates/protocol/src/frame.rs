//! The sensor frame and its encoding.

use crate::error::DecodeError;
use crate::{
    crc32c, COBS_LEN, CRC_COVERED_LEN, DELIMITER, PAYLOAD_LEN, PROTOCOL_VERSION, WIRE_LEN,
};

/// Number of ADC channels in a frame.
pub const CHANNELS: usize = 4;

/// The four sensor channels, in frame order: a sample is `[D1, D2, D3, P]`.
///
/// The one definition of a channel for the whole workspace (`crackbot-dsp` re-exports it). With the
/// `serde` feature it serialises as its name (`"D1"`, `"D2"`, `"D3"`, `"P"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Channel {
    /// Left deformation fibre.
    D1 = 0,
    /// Right deformation fibre.
    D2 = 1,
    /// Back (normal) deformation fibre.
    D3 = 2,
    /// Proximity fibre.
    P = 3,
}

impl Channel {
    /// All channels in frame order.
    pub const ALL: [Channel; CHANNELS] = [Channel::D1, Channel::D2, Channel::D3, Channel::P];

    /// Index into a sample or a frame's channels `[D1, D2, D3, P]`.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Short name as used in the papers and in recordings (`D1`, `D2`, `D3`, `P`).
    pub const fn name(self) -> &'static str {
        match self {
            Channel::D1 => "D1",
            Channel::D2 => "D2",
            Channel::D3 => "D3",
            Channel::P => "P",
        }
    }
}

impl core::fmt::Display for Channel {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// Status flags of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Flags(pub u8);

impl Flags {
    /// Bit of the overrun flag: at least one sample before this one was dropped because the UART
    /// could not keep up (the sequence number shows how many).
    pub const OVERRUN: u8 = 1 << 4;
    /// Mask of the bits defined by this protocol version.
    pub const DEFINED: u8 = 0x1F;

    /// No flag set.
    pub const fn empty() -> Self {
        Flags(0)
    }
    /// Bit of the saturation flag of `channel`.
    pub const fn saturation_bit(channel: Channel) -> u8 {
        1 << channel as u8
    }
    /// Whether `channel` hit an ADC rail in this sample.
    pub const fn saturated(self, channel: Channel) -> bool {
        self.0 & Self::saturation_bit(channel) != 0
    }
    /// Whether any channel hit an ADC rail.
    pub const fn any_saturated(self) -> bool {
        self.0 & 0x0F != 0
    }
    /// Whether samples were dropped before this one.
    pub const fn overrun(self) -> bool {
        self.0 & Self::OVERRUN != 0
    }
    /// Sets or clears the saturation flag of `channel`.
    pub fn set_saturated(&mut self, channel: Channel, on: bool) {
        self.set_bit(Self::saturation_bit(channel), on);
    }
    /// Sets or clears the overrun flag.
    pub fn set_overrun(&mut self, on: bool) {
        self.set_bit(Self::OVERRUN, on);
    }
    fn set_bit(&mut self, bit: u8, on: bool) {
        if on {
            self.0 |= bit;
        } else {
            self.0 &= !bit;
        }
    }
}

/// One sample of the sensor as sent by the firmware.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Frame {
    /// Sequence number, incremented (wrapping) for every 400 Hz tick, sent or not.
    pub seq: u16,
    /// Device clock at the sample, µs, wrapping.
    pub timestamp_us: u32,
    /// Raw ADC counts of D1, D2, D3, P.
    pub channels: [u16; CHANNELS],
    /// Status flags.
    pub flags: Flags,
}

impl Frame {
    /// Raw ADC count of one channel.
    pub const fn channel(&self, channel: Channel) -> u16 {
        self.channels[channel.index()]
    }

    /// The payload: header, channels and CRC-32C.
    pub fn to_payload(&self) -> [u8; PAYLOAD_LEN] {
        let mut p = [0u8; PAYLOAD_LEN];
        p[0] = PROTOCOL_VERSION;
        p[1] = self.flags.0;
        p[2..4].copy_from_slice(&self.seq.to_le_bytes());
        p[4..8].copy_from_slice(&self.timestamp_us.to_le_bytes());
        for (i, value) in self.channels.iter().enumerate() {
            p[8 + 2 * i..10 + 2 * i].copy_from_slice(&value.to_le_bytes());
        }
        let crc = crc32c(&p[..CRC_COVERED_LEN]);
        p[CRC_COVERED_LEN..].copy_from_slice(&crc.to_le_bytes());
        p
    }

    /// Parses and checks a payload (version, CRC, reserved flag bits).
    pub fn from_payload(p: &[u8; PAYLOAD_LEN]) -> Result<Self, DecodeError> {
        let expected = u32::from_le_bytes([p[16], p[17], p[18], p[19]]);
        let actual = crc32c(&p[..CRC_COVERED_LEN]);
        if expected != actual {
            return Err(DecodeError::Crc { expected, actual });
        }
        if p[0] != PROTOCOL_VERSION {
            return Err(DecodeError::UnsupportedVersion { version: p[0] });
        }
        if p[1] & !Flags::DEFINED != 0 {
            return Err(DecodeError::ReservedFlags { flags: p[1] });
        }
        let mut channels = [0u16; CHANNELS];
        for (i, value) in channels.iter_mut().enumerate() {
            *value = u16::from_le_bytes([p[8 + 2 * i], p[9 + 2 * i]]);
        }
        Ok(Frame {
            seq: u16::from_le_bytes([p[2], p[3]]),
            timestamp_us: u32::from_le_bytes([p[4], p[5], p[6], p[7]]),
            channels,
            flags: Flags(p[1]),
        })
    }

    /// The frame as it goes on the wire: `00`, COBS(payload), `00`.
    pub fn to_wire(&self) -> [u8; WIRE_LEN] {
        let mut wire = [DELIMITER; WIRE_LEN];
        let written = cobs::encode(&self.to_payload(), &mut wire[1..1 + COBS_LEN]);
        debug_assert_eq!(written, COBS_LEN);
        wire
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wire_has_no_inner_zero_and_fixed_length() {
        let frame = Frame {
            seq: 0,
            timestamp_us: 0,
            channels: [0; 4],
            flags: Flags(0),
        };
        let wire = frame.to_wire();
        assert_eq!(wire[0], 0);
        assert_eq!(wire[WIRE_LEN - 1], 0);
        assert!(wire[1..WIRE_LEN - 1].iter().all(|&b| b != 0));
    }

    #[test]
    fn flags_roundtrip() {
        let mut f = Flags::empty();
        f.set_saturated(Channel::D3, true);
        f.set_overrun(true);
        assert!(f.saturated(Channel::D3) && !f.saturated(Channel::D1) && f.overrun());
        f.set_saturated(Channel::D3, false);
        assert!(!f.any_saturated());
    }
}
