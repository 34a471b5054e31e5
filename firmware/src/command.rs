//! Commands the host may send to the board over the UART's receive line.
//!
//! One command is defined: **encode**, `E` followed by 30 hexadecimal digits and a newline
//! (`\n`, an optional `\r` before it is ignored). The digits are, as big-endian numbers, the
//! flags (2 digits), the sequence number (4), the timestamp in µs (8) and the channels D1, D2,
//! D3, P (4 each). The board answers with that frame's wire bytes, encoded by the same code as
//! its sampled frames, in the middle of its stream. It is how the golden vectors
//! (`crates/protocol/golden`) are checked on the board image itself, and how a user checks a
//! freshly flashed board without the finger: `printf 'E00000000000000000258' …`.
//!
//! [`CommandReader`] takes the received bytes one at a time (from the UART's receive interrupt)
//! and reports each complete line; a line that is too long, has a digit that is not hexadecimal
//! or names no known command is an error, and the reader starts afresh after its newline.

use crackbot_protocol::{Flags, Frame};
use heapless::Vec;

/// Longest line: `E` + 30 digits + `\r`.
pub const MAX_LINE: usize = 32;

/// A command the board understood.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// Send this frame's wire bytes.
    Encode(Frame),
}

/// Why a received line is not a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandError {
    /// The line had more than [`MAX_LINE`] bytes.
    TooLong,
    /// The line starts with a byte that names no command.
    Unknown(u8),
    /// The encode command needs 30 digits; this many were given.
    WrongLength(usize),
    /// A byte that is not a hexadecimal digit.
    NotHex(u8),
}

/// Parses one line without its newline.
pub fn parse(line: &[u8]) -> Result<Command, CommandError> {
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    match line.split_first() {
        Some((b'E', digits)) => parse_encode(digits).map(Command::Encode),
        Some((&other, _)) => Err(CommandError::Unknown(other)),
        None => Err(CommandError::WrongLength(0)),
    }
}

fn parse_encode(digits: &[u8]) -> Result<Frame, CommandError> {
    if digits.len() != 30 {
        return Err(CommandError::WrongLength(digits.len()));
    }
    let flags = hex(&digits[..2])?;
    let seq = hex(&digits[2..6])?;
    let timestamp_us = hex(&digits[6..14])?;
    let mut channels = [0u16; 4];
    for (i, channel) in channels.iter_mut().enumerate() {
        let start = 14 + 4 * i;
        *channel = hex(&digits[start..start + 4])? as u16;
    }
    Ok(Frame {
        seq: seq as u16,
        timestamp_us,
        channels,
        flags: Flags(flags as u8),
    })
}

fn hex(digits: &[u8]) -> Result<u32, CommandError> {
    let mut value = 0u32;
    for &d in digits {
        let nibble = match d {
            b'0'..=b'9' => d - b'0',
            b'a'..=b'f' => d - b'a' + 10,
            b'A'..=b'F' => d - b'A' + 10,
            _ => return Err(CommandError::NotHex(d)),
        };
        value = (value << 4) | u32::from(nibble);
    }
    Ok(value)
}

/// Collects received bytes into lines and parses each.
#[derive(Debug, Default)]
pub struct CommandReader {
    line: Vec<u8, MAX_LINE>,
    overflow: bool,
}

impl CommandReader {
    /// An empty reader.
    pub const fn new() -> Self {
        CommandReader {
            line: Vec::new(),
            overflow: false,
        }
    }

    /// Takes one received byte; at a newline, the line's command or error. Empty lines are
    /// ignored.
    pub fn push(&mut self, byte: u8) -> Option<Result<Command, CommandError>> {
        if byte != b'\n' {
            if self.line.push(byte).is_err() {
                self.overflow = true;
            }
            return None;
        }
        let result = if self.overflow {
            Some(Err(CommandError::TooLong))
        } else if self.line.is_empty() {
            None
        } else {
            Some(parse(&self.line))
        };
        self.line.clear();
        self.overflow = false;
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed(reader: &mut CommandReader, bytes: &[u8]) -> Option<Result<Command, CommandError>> {
        let mut last = None;
        for &b in bytes {
            if let Some(r) = reader.push(b) {
                last = Some(r);
            }
        }
        last
    }

    #[test]
    fn an_encode_line_gives_its_frame() {
        let mut r = CommandReader::new();
        let got = feed(&mut r, b"E10002a00019a280280 1ae02c60190\n");
        // A space is not a digit.
        assert_eq!(got, Some(Err(CommandError::NotHex(b' '))));
        let got = feed(&mut r, b"E10002a00019a28028001ae02c60190\r\n");
        let frame = Frame {
            seq: 42,
            timestamp_us: 105_000,
            channels: [640, 430, 710, 400],
            flags: Flags(0x10),
        };
        assert_eq!(got, Some(Ok(Command::Encode(frame))));
    }

    #[test]
    fn bad_lines_are_errors_and_the_next_line_reads_cleanly() {
        let mut r = CommandReader::new();
        assert_eq!(feed(&mut r, b"X\n"), Some(Err(CommandError::Unknown(b'X'))));
        assert_eq!(
            feed(&mut r, b"E10002a00019a28028001ae02c6019g\n"),
            Some(Err(CommandError::NotHex(b'g')))
        );
        assert_eq!(feed(&mut r, &[b'E'; 40]), None);
        assert_eq!(feed(&mut r, b"\n"), Some(Err(CommandError::TooLong)));
        assert_eq!(feed(&mut r, b"\n"), None);
        assert!(matches!(
            feed(&mut r, b"EFFFFFFFFFFFFFFFFFFFFFFFFFFFFFF\n"),
            Some(Ok(Command::Encode(Frame { seq: 0xFFFF, .. })))
        ));
    }
}
