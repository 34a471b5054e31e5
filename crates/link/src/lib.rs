//! The authenticated link between the host and the manipulator controller of the
//! crack-inspection robot: versioned compact messages over UDP, signed with HMAC-SHA256 under a
//! pre-shared key, with a sliding anti-replay window, challenge–response resynchronisation after
//! restarts, acknowledgements, retries and timeouts.
//!
//! * The core is `no_std` and allocation-free, for the controller's microcontroller: the messages
//!   ([`Message`]), the packet codec ([`wire`]), the key and tag ([`Key`], [`Signer`]), the
//!   replay window ([`ReplayWindow`]) and the whole protocol as a state machine without I/O
//!   ([`LinkCore`]: datagrams in, events and replies out; the caller moves the bytes and keeps
//!   the time).
//! * With the `std` feature (default): [`LinkEndpoint`] over a `std::net::UdpSocket`
//!   ([`LinkEndpoint::send_reliable`], [`LinkEndpoint::send_unreliable`],
//!   [`LinkEndpoint::recv`], [`LinkStats`] of everything dropped and why), the key file
//!   ([`Key::from_file`]), the epoch file ([`EpochFile`]) and fault injection on the send path
//!   ([`FaultInjector`]).
//!
//! # Use (std)
//!
//! ```no_run
//! use std::time::Duration;
//! use crackbot_link::{EpochSource, Key, LinkConfig, LinkEndpoint, Message, MoveTo, Pose, Security};
//!
//! # fn main() -> Result<(), crackbot_link::LinkError> {
//! let key = Key::from_file("/etc/crackbot/link.key")?; // 0600, hex
//! let config = LinkConfig::host(
//!     Security::Signed(key),
//!     EpochSource::File("/var/lib/crackbot/link-host.epoch".into()),
//! );
//! let mut link = LinkEndpoint::bind(
//!     "0.0.0.0:47100".parse().unwrap(),
//!     "192.168.7.2:47100".parse().unwrap(),
//!     config,
//! )?;
//! let pose = Pose { x_mm: 120.0, y_mm: 40.0, z_mm: 10.0 };
//! let controller_now_us = 0; // the newest State's controller_time_us (plus its age)
//! let valid_until_us = controller_now_us + 1_000_000; // not to start more than 1 s late
//! let seq = link.send_reliable(&Message::MoveTo(MoveTo { pose, speed_mm_s: 50.0, valid_until_us }))?;
//! while let Some(r) = link.recv(Duration::from_millis(20))? {
//!     match r.message {
//!         Message::State(s) => println!("{:?} at {} µs", s.pose, s.controller_time_us),
//!         Message::Error(e) if e.seq == seq => eprintln!("refused: {:?} {}", e.code, e.text),
//!         _ => {}
//!     }
//! }
//! println!("{:?}", link.stats());
//! # Ok(()) }
//! ```
//!
//! The controller's end is the same with [`LinkConfig::controller`] (or [`LinkCore`] on a
//! microcontroller). Both ends must call [`LinkEndpoint::recv`] regularly: it answers
//! challenges and acknowledges.
//!
//! # Choices
//!
//! * Restart safety comes from an **epoch in the header**: the sender takes a new epoch at every
//!   start (persisted by [`EpochFile`]) and counts packets from 1 within it; the receiver
//!   persists nothing and, after its own start or when the peer's epoch changes, accepts the
//!   peer's packets only from the counter of a fresh answer to its challenge on.
//! * A counter, not a timestamp: the controller needs no clock, and a "future" value has no
//!   meaning beyond a jump limit (1024 packets) that is answered by a challenge, not adopted.
//! * The payload is postcard (stable, documented, `no_std`); the header is fixed-layout so that a
//!   packet can be checked and authenticated before anything is decoded.
//!
//! The specification follows.
//!
#![doc = include_str!("../docs/wire-format.md")]
#![no_std]

#[cfg(feature = "std")]
extern crate std;

mod auth;
mod message;
mod replay;
mod session;
pub mod wire;

pub use auth::{Key, KeyError, Signer, KEY_MAX_LEN, KEY_MIN_LEN, TAG_LEN};
pub use message::{
    Contact, ErrorCode, ErrorReport, ErrorText, Message, Mode, MoveTo, Point2, Pose, Slide, State,
    Velocity, ERROR_TEXT_MAX, SCHEMA, SCHEMA_HASH,
};
pub use replay::{ReplayWindow, Verdict, DEFAULT_MAX_JUMP, WINDOW};
pub use session::{
    ConfigError, CoreConfig, Event, Incoming, LinkCore, LinkStats, Reject, Sent,
    DEFAULT_CHALLENGE_INTERVAL_MS, NODE_CONTROLLER, NODE_HOST,
};
pub use wire::{Body, DecodeError, EncodeError, Header, Kind, Packet, MAX_DATAGRAM, MAX_PAYLOAD};

#[cfg(feature = "std")]
mod udp;
#[cfg(feature = "std")]
pub use udp::{
    EpochError, EpochFile, EpochSource, Fate, FaultConfig, FaultInjector, FaultStats, KeyFileError,
    LinkConfig, LinkEndpoint, LinkError, PacketInfo, Received, Security,
};

/// The checked-in golden vectors (`golden/vectors.json`, written by `golden/generate.py`, an
/// independent Python implementation of the wire format, the tag and the replay window).
pub const GOLDEN_VECTORS_JSON: &str = include_str!("../golden/vectors.json");
