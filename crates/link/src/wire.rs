//! The packet: fixed little-endian header, payload, tag. See the crate docs for the layout.

use core::fmt;

use crate::auth::{Signer, TAG_LEN};
use crate::message::Message;

/// First two bytes of every packet: `"CL"`.
pub const MAGIC: [u8; 2] = *b"CL";
/// Version of the packet format (header layout, kinds, signing input).
pub const WIRE_VERSION: u8 = 1;
/// Bytes of the header.
pub const HEADER_LEN: usize = 34;
/// Largest payload, bytes.
pub const MAX_PAYLOAD: usize = 256;
/// Largest packet: header, payload and tag.
pub const MAX_DATAGRAM: usize = HEADER_LEN + MAX_PAYLOAD + TAG_LEN;
/// Bytes of the payload of a [`Kind::Response`]: the echoed epoch (4) and counter (8).
pub const RESPONSE_LEN: usize = 12;

/// Flag bit: a [`TAG_LEN`]-byte tag follows the payload.
pub const FLAG_SIGNED: u8 = 0x01;
/// Flag bit: the receiver must acknowledge this packet (data packets only).
pub const FLAG_ACK_REQUESTED: u8 = 0x02;
const FLAGS_KNOWN: u8 = FLAG_SIGNED | FLAG_ACK_REQUESTED;

/// What a packet carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Kind {
    /// An application [`Message`].
    Data = 0,
    /// Acknowledges the data packet whose sequence number is in the header.
    Ack = 1,
    /// Asks the peer to prove it is live (see the crate docs); its own epoch and counter are the
    /// challenge.
    Challenge = 2,
    /// Answers a challenge: the payload echoes its epoch and counter.
    Response = 3,
}

impl Kind {
    fn from_byte(b: u8) -> Option<Self> {
        Some(match b {
            0 => Kind::Data,
            1 => Kind::Ack,
            2 => Kind::Challenge,
            3 => Kind::Response,
            _ => return None,
        })
    }
}

/// The header fields (the magic, version, flags other than ack-requested, kind and payload
/// length are derived when encoding).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Header {
    /// The receiver must acknowledge (data packets only).
    pub ack_requested: bool,
    /// Node id of the sender (host 1, controller 2 by default).
    pub sender: u8,
    /// Link id: packets of another link are refused even under the same key.
    pub link_id: u16,
    /// Schema hash of the sender's message definitions.
    pub schema: [u8; 8],
    /// The sender's epoch: never the same twice for a key, sender and link (a new one each
    /// start).
    pub epoch: u32,
    /// The sender's packet counter within the epoch: +1 for every packet it sends, retries,
    /// acknowledgements and challenges included; starts at 1.
    pub counter: u64,
    /// Message sequence number (data: the message, kept by retries; ack: the acknowledged
    /// message's; challenge and response: 0).
    pub seq: u32,
}

/// What follows the header.
#[derive(Clone, Debug, PartialEq)]
pub enum Body {
    /// An application message (postcard).
    Data(Message),
    /// An acknowledgement (empty payload).
    Ack,
    /// A challenge (empty payload).
    Challenge,
    /// The answer to the challenge sent with this epoch and counter.
    Response {
        /// The challenge's epoch.
        epoch: u32,
        /// The challenge's counter.
        counter: u64,
    },
}

impl Body {
    /// The packet kind of this body.
    pub fn kind(&self) -> Kind {
        match self {
            Body::Data(_) => Kind::Data,
            Body::Ack => Kind::Ack,
            Body::Challenge => Kind::Challenge,
            Body::Response { .. } => Kind::Response,
        }
    }
}

/// A decoded, verified packet.
#[derive(Clone, Debug, PartialEq)]
pub struct Packet {
    /// Its header.
    pub header: Header,
    /// Its body.
    pub body: Body,
}

/// Why a packet could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is too small (give it [`MAX_DATAGRAM`] bytes).
    BufferTooSmall,
    /// The message encodes to more than [`MAX_PAYLOAD`] bytes.
    PayloadTooLong,
    /// Only data packets may request an acknowledgement; control packets carry sequence 0.
    BadControl,
    /// The counter or sequence number space of this epoch is used up: start a new epoch.
    Exhausted,
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            EncodeError::BufferTooSmall => "output buffer too small for the packet",
            EncodeError::PayloadTooLong => "message longer than the largest payload",
            EncodeError::BadControl => "ack requested or sequence number on a control packet",
            EncodeError::Exhausted => "counter or sequence space of this epoch used up",
        })
    }
}

impl core::error::Error for EncodeError {}

/// Why bytes are not a valid packet (or, for [`decode`], not an authentic one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum DecodeError {
    /// Shorter than the header.
    Truncated,
    /// Does not start with [`MAGIC`].
    BadMagic,
    /// A version other than [`WIRE_VERSION`].
    UnsupportedVersion {
        /// The version byte.
        version: u8,
    },
    /// A flag bit that version 1 does not define is set.
    ReservedFlags {
        /// The flags byte.
        flags: u8,
    },
    /// A kind byte other than 0..=3.
    UnknownKind {
        /// The kind byte.
        kind: u8,
    },
    /// The datagram length is not header + payload length + tag.
    LengthMismatch {
        /// Length the header announces.
        expected: usize,
        /// Length received.
        actual: usize,
    },
    /// The payload length exceeds [`MAX_PAYLOAD`].
    PayloadTooLong {
        /// The payload length field.
        len: usize,
    },
    /// A control packet with a payload length, ack flag or sequence number it may not have.
    BadControl,
    /// The payload is not a postcard [`Message`] of this schema (unknown variant, bad UTF-8,
    /// text too long, truncated...).
    Payload,
    /// The payload decodes but is not the canonical encoding of the message (trailing bytes,
    /// overlong varints).
    NonCanonical,
    /// [`decode`] with a signer: the packet has no tag.
    Unsigned,
    /// [`decode`] without a signer: the packet has a tag.
    UnexpectedTag,
    /// [`decode`] with a signer: the tag is wrong.
    BadTag,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::Truncated => f.write_str("shorter than the header"),
            DecodeError::BadMagic => f.write_str("bad magic"),
            DecodeError::UnsupportedVersion { version } => {
                write!(f, "unsupported wire version {version}")
            }
            DecodeError::ReservedFlags { flags } => write!(f, "reserved flag bits in {flags:#04x}"),
            DecodeError::UnknownKind { kind } => write!(f, "unknown packet kind {kind}"),
            DecodeError::LengthMismatch { expected, actual } => {
                write!(f, "length {actual}, header announces {expected}")
            }
            DecodeError::PayloadTooLong { len } => write!(f, "payload length {len} over the limit"),
            DecodeError::BadControl => f.write_str("malformed control packet"),
            DecodeError::Payload => f.write_str("payload is not a message of this schema"),
            DecodeError::NonCanonical => f.write_str("payload is not canonically encoded"),
            DecodeError::Unsigned => f.write_str("packet is not signed"),
            DecodeError::UnexpectedTag => f.write_str("packet is signed but no key is configured"),
            DecodeError::BadTag => f.write_str("bad authentication tag"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// A packet split into its parts, before its tag is checked or its payload decoded.
#[derive(Clone, Copy, Debug)]
pub struct Parsed<'a> {
    /// The header fields.
    pub header: Header,
    /// The kind.
    pub kind: Kind,
    /// Whether a tag is present.
    pub signed: bool,
    /// The payload bytes.
    pub payload: &'a [u8],
    /// The bytes the tag covers (header and payload).
    pub signed_bytes: &'a [u8],
    /// The tag (empty when unsigned).
    pub tag: &'a [u8],
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[at..at + 4]);
    u32::from_le_bytes(a)
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// Splits `datagram` into header, payload and tag, checking the layout (not the tag, not the
/// payload encoding).
pub fn parse(datagram: &[u8]) -> Result<Parsed<'_>, DecodeError> {
    let d = datagram;
    if d.len() < HEADER_LEN {
        return Err(DecodeError::Truncated);
    }
    if d[0..2] != MAGIC {
        return Err(DecodeError::BadMagic);
    }
    if d[2] != WIRE_VERSION {
        return Err(DecodeError::UnsupportedVersion { version: d[2] });
    }
    let flags = d[3];
    if flags & !FLAGS_KNOWN != 0 {
        return Err(DecodeError::ReservedFlags { flags });
    }
    let kind = Kind::from_byte(d[4]).ok_or(DecodeError::UnknownKind { kind: d[4] })?;
    let mut schema = [0u8; 8];
    schema.copy_from_slice(&d[8..16]);
    let header = Header {
        ack_requested: flags & FLAG_ACK_REQUESTED != 0,
        sender: d[5],
        link_id: u16_at(d, 6),
        schema,
        epoch: u32_at(d, 16),
        counter: u64_at(d, 20),
        seq: u32_at(d, 28),
    };
    let len = usize::from(u16_at(d, 32));
    if len > MAX_PAYLOAD {
        return Err(DecodeError::PayloadTooLong { len });
    }
    let signed = flags & FLAG_SIGNED != 0;
    let expected = HEADER_LEN + len + if signed { TAG_LEN } else { 0 };
    if d.len() != expected {
        return Err(DecodeError::LengthMismatch {
            expected,
            actual: d.len(),
        });
    }
    let control_ok = match kind {
        Kind::Data => len >= 1,
        Kind::Ack => len == 0 && !header.ack_requested,
        Kind::Challenge => len == 0 && !header.ack_requested && header.seq == 0,
        Kind::Response => len == RESPONSE_LEN && !header.ack_requested && header.seq == 0,
    };
    if !control_ok {
        return Err(DecodeError::BadControl);
    }
    let body_end = HEADER_LEN + len;
    Ok(Parsed {
        header,
        kind,
        signed,
        payload: &d[HEADER_LEN..body_end],
        signed_bytes: &d[..body_end],
        tag: &d[body_end..],
    })
}

impl Parsed<'_> {
    /// Whether the packet carries a valid tag under `signer` (constant-time comparison).
    pub fn verify(&self, signer: &Signer) -> bool {
        self.signed && signer.verify(self.signed_bytes, self.tag)
    }

    /// The body: for data, the postcard payload decoded, which must be the canonical encoding
    /// of the message (re-encoding gives the same bytes).
    pub fn body(&self) -> Result<Body, DecodeError> {
        Ok(match self.kind {
            Kind::Data => Body::Data(decode_message(self.payload)?),
            Kind::Ack => Body::Ack,
            Kind::Challenge => Body::Challenge,
            Kind::Response => Body::Response {
                epoch: u32_at(self.payload, 0),
                counter: u64_at(self.payload, 4),
            },
        })
    }
}

/// Decodes a data payload: the canonical postcard encoding of a [`Message`], nothing after it.
pub fn decode_message(payload: &[u8]) -> Result<Message, DecodeError> {
    let (message, rest): (Message, &[u8]) =
        postcard::take_from_bytes(payload).map_err(|_| DecodeError::Payload)?;
    if !rest.is_empty() {
        return Err(DecodeError::NonCanonical);
    }
    let mut again = [0u8; MAX_PAYLOAD];
    match postcard::to_slice(&message, &mut again) {
        Ok(bytes) if *bytes == *payload => Ok(message),
        _ => Err(DecodeError::NonCanonical),
    }
}

/// Encodes a message as a data payload into `out`, returning its length.
pub fn encode_message(message: &Message, out: &mut [u8]) -> Result<usize, EncodeError> {
    let room = out.len().min(MAX_PAYLOAD);
    match postcard::to_slice(message, &mut out[..room]) {
        Ok(bytes) => Ok(bytes.len()),
        Err(_) if room < MAX_PAYLOAD => Err(EncodeError::BufferTooSmall),
        Err(_) => Err(EncodeError::PayloadTooLong),
    }
}

/// Parses, authenticates and decodes `datagram`. With a signer the packet must carry a valid
/// tag; without one it must carry none. Checks nothing of the header's meaning (schema, link,
/// sender, replay): that is [`crate::LinkCore`]'s job.
pub fn decode(datagram: &[u8], signer: Option<&Signer>) -> Result<Packet, DecodeError> {
    let p = parse(datagram)?;
    match (signer, p.signed) {
        (Some(_), false) => return Err(DecodeError::Unsigned),
        (None, true) => return Err(DecodeError::UnexpectedTag),
        (Some(s), true) if !p.verify(s) => return Err(DecodeError::BadTag),
        _ => {}
    }
    Ok(Packet {
        header: p.header,
        body: p.body()?,
    })
}

/// Encodes a packet into `out` and returns its length: header, payload and, with a signer,
/// the tag over both (computed now: call it again to re-sign with a new counter).
pub fn encode(
    header: &Header,
    body: &Body,
    signer: Option<&Signer>,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let kind = body.kind();
    if kind != Kind::Data && header.ack_requested
        || matches!(kind, Kind::Challenge | Kind::Response) && header.seq != 0
    {
        return Err(EncodeError::BadControl);
    }
    if out.len() < HEADER_LEN {
        return Err(EncodeError::BufferTooSmall);
    }
    let len = match body {
        Body::Data(m) => encode_message(m, &mut out[HEADER_LEN..])?,
        Body::Ack | Body::Challenge => 0,
        Body::Response { epoch, counter } => {
            if out.len() < HEADER_LEN + RESPONSE_LEN {
                return Err(EncodeError::BufferTooSmall);
            }
            out[HEADER_LEN..HEADER_LEN + 4].copy_from_slice(&epoch.to_le_bytes());
            out[HEADER_LEN + 4..HEADER_LEN + 12].copy_from_slice(&counter.to_le_bytes());
            RESPONSE_LEN
        }
    };
    let total = HEADER_LEN + len + if signer.is_some() { TAG_LEN } else { 0 };
    if out.len() < total {
        return Err(EncodeError::BufferTooSmall);
    }
    let mut flags = 0;
    if signer.is_some() {
        flags |= FLAG_SIGNED;
    }
    if header.ack_requested {
        flags |= FLAG_ACK_REQUESTED;
    }
    out[0..2].copy_from_slice(&MAGIC);
    out[2] = WIRE_VERSION;
    out[3] = flags;
    out[4] = kind as u8;
    out[5] = header.sender;
    out[6..8].copy_from_slice(&header.link_id.to_le_bytes());
    out[8..16].copy_from_slice(&header.schema);
    out[16..20].copy_from_slice(&header.epoch.to_le_bytes());
    out[20..28].copy_from_slice(&header.counter.to_le_bytes());
    out[28..32].copy_from_slice(&header.seq.to_le_bytes());
    // len ≤ MAX_PAYLOAD < 65 536.
    out[32..34].copy_from_slice(&(len as u16).to_le_bytes());
    if let Some(s) = signer {
        let body_end = HEADER_LEN + len;
        let tag = s.tag(&out[..body_end]);
        out[body_end..total].copy_from_slice(&tag);
    }
    Ok(total)
}

/// Rewrites the counter of the encoded packet `datagram` and, with a signer, its tag: how a
/// retry is re-signed at send time. The packet must have been encoded with the same signer
/// (or none).
pub fn resign(
    datagram: &mut [u8],
    counter: u64,
    signer: Option<&Signer>,
) -> Result<(), DecodeError> {
    let p = parse(datagram)?;
    let body_end = p.signed_bytes.len();
    if p.signed != signer.is_some() {
        return Err(if p.signed {
            DecodeError::UnexpectedTag
        } else {
            DecodeError::Unsigned
        });
    }
    datagram[20..28].copy_from_slice(&counter.to_le_bytes());
    if let Some(s) = signer {
        let tag = s.tag(&datagram[..body_end]);
        datagram[body_end..body_end + TAG_LEN].copy_from_slice(&tag);
    }
    Ok(())
}
