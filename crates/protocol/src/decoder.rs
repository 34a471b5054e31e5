//! Streaming frame decoder.

use crate::error::DecodeError;
use crate::{Frame, COBS_LEN, DELIMITER, PAYLOAD_LEN};

/// Counters kept by a [`Decoder`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct DecoderStats {
    /// Bytes fed, delimiters included.
    pub bytes: u64,
    /// Valid frames decoded.
    pub frames: u64,
    /// Chunks rejected for a CRC mismatch.
    pub crc_errors: u64,
    /// Chunks rejected as invalid COBS.
    pub cobs_errors: u64,
    /// Chunks shorter than a frame.
    pub truncated: u64,
    /// Runs of bytes longer than a frame without a delimiter.
    pub overlong: u64,
    /// Frames of an unknown protocol version or with reserved flag bits set.
    pub version_errors: u64,
    /// Bytes thrown away with rejected chunks.
    pub discarded_bytes: u64,
}

impl DecoderStats {
    /// Times the decoder threw bytes away and resynchronised at the next delimiter (one per
    /// rejected chunk).
    pub const fn resyncs(&self) -> u64 {
        self.crc_errors + self.cobs_errors + self.truncated + self.overlong + self.version_errors
    }
}

/// Streaming decoder: feed it bytes in chunks of any size, get frames and errors.
///
/// Rules: bytes between two delimiters form a chunk. An empty chunk is ignored (the wire format
/// puts a delimiter before and after every frame). A chunk of exactly [`COBS_LEN`] bytes is
/// decoded and checked (COBS, CRC-32C, version, flags); any other chunk is reported as an error
/// and dropped, and decoding resumes at the next delimiter. A run longer than a frame is not
/// buffered: its bytes are only counted. The decoder holds one frame's worth of state (21 bytes),
/// never allocates and never panics.
#[derive(Debug, Clone)]
pub struct Decoder {
    buf: [u8; COBS_LEN],
    len: usize,
    /// Bytes seen in the current chunk once it is known to be too long.
    overlong: usize,
    stats: DecoderStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder waiting for the first delimiter-bounded chunk.
    pub const fn new() -> Self {
        Decoder {
            buf: [0; COBS_LEN],
            len: 0,
            overlong: 0,
            stats: DecoderStats {
                bytes: 0,
                frames: 0,
                crc_errors: 0,
                cobs_errors: 0,
                truncated: 0,
                overlong: 0,
                version_errors: 0,
                discarded_bytes: 0,
            },
        }
    }

    /// Counters so far.
    pub const fn stats(&self) -> &DecoderStats {
        &self.stats
    }

    /// Bytes of an unfinished chunk held back until its delimiter arrives.
    pub const fn pending(&self) -> usize {
        if self.overlong > 0 {
            self.overlong
        } else {
            self.len
        }
    }

    /// Feeds `bytes`; calls `sink` once for every completed chunk that was not empty, in order.
    pub fn feed<F>(&mut self, mut bytes: &[u8], mut sink: F)
    where
        F: FnMut(Result<Frame, DecodeError>),
    {
        self.stats.bytes += bytes.len() as u64;
        while let Some(zero) = memchr::memchr(DELIMITER, bytes) {
            let (segment, rest) = bytes.split_at(zero);
            if self.len == 0 && self.overlong == 0 {
                // Fast path: a whole chunk inside this slice, nothing buffered.
                if !segment.is_empty() {
                    let result = Self::decode_chunk(segment);
                    self.account(&result, segment.len());
                    sink(result);
                }
            } else {
                self.append(segment);
                if let Some(result) = self.finish_chunk() {
                    sink(result);
                }
            }
            bytes = rest.get(1..).unwrap_or(&[]);
        }
        self.append(bytes);
    }

    /// Forgets any partial chunk (e.g. after reopening a port). Counters are kept.
    pub fn reset(&mut self) {
        self.len = 0;
        self.overlong = 0;
    }

    fn append(&mut self, segment: &[u8]) {
        if segment.is_empty() {
            return;
        }
        if self.overlong > 0 {
            self.overlong += segment.len();
            return;
        }
        let end = self.len + segment.len();
        if let Some(dst) = self.buf.get_mut(self.len..end) {
            dst.copy_from_slice(segment);
            self.len = end;
        } else {
            self.overlong = end;
            self.len = 0;
        }
    }

    fn finish_chunk(&mut self) -> Option<Result<Frame, DecodeError>> {
        let (result, len) = if self.overlong > 0 {
            (
                Err(DecodeError::Overlong { len: self.overlong }),
                self.overlong,
            )
        } else if self.len == 0 {
            return None;
        } else {
            let buf = self.buf;
            (Self::decode_chunk(&buf[..self.len]), self.len)
        };
        self.reset();
        self.account(&result, len);
        Some(result)
    }

    fn decode_chunk(chunk: &[u8]) -> Result<Frame, DecodeError> {
        if chunk.len() > COBS_LEN {
            return Err(DecodeError::Overlong { len: chunk.len() });
        }
        if chunk.len() < COBS_LEN {
            return Err(DecodeError::Truncated { len: chunk.len() });
        }
        let mut payload = [0u8; PAYLOAD_LEN];
        // `chunk` holds no delimiter and is exactly COBS_LEN long (checked above), so the whole
        // chunk is parsed; it must decode to exactly one payload.
        match cobs::decode(chunk, &mut payload) {
            Ok(PAYLOAD_LEN) => {}
            _ => return Err(DecodeError::Cobs),
        }
        Frame::from_payload(&payload)
    }

    fn account(&mut self, result: &Result<Frame, DecodeError>, len: usize) {
        let s = &mut self.stats;
        match result {
            Ok(_) => {
                s.frames += 1;
                return;
            }
            Err(DecodeError::Crc { .. }) => s.crc_errors += 1,
            Err(DecodeError::Cobs) => s.cobs_errors += 1,
            Err(DecodeError::Truncated { .. }) => s.truncated += 1,
            Err(DecodeError::Overlong { .. }) => s.overlong += 1,
            Err(DecodeError::UnsupportedVersion { .. } | DecodeError::ReservedFlags { .. }) => {
                s.version_errors += 1;
            }
        }
        s.discarded_bytes += len as u64;
    }
}
