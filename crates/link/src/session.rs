//! The link state machine without input or output ("sans-IO"): what the UDP endpoint of the
//! host and the controller firmware both run. It turns datagrams into events and replies, and
//! messages into datagrams; the caller moves the bytes and keeps the time.

use core::fmt;

use crate::auth::Signer;
use crate::message::{Message, SCHEMA_HASH};
use crate::replay::{ReplayWindow, Verdict, DEFAULT_MAX_JUMP};
use crate::wire::{self, Body, DecodeError, EncodeError, Header, Kind};

/// Node id of the host.
pub const NODE_HOST: u8 = 1;
/// Node id of the manipulator controller.
pub const NODE_CONTROLLER: u8 = 2;

/// Default shortest interval between two challenges, ms.
pub const DEFAULT_CHALLENGE_INTERVAL_MS: u64 = 20;

/// Who talks to whom, and the replay limits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoreConfig {
    /// Link id (the same on both ends; packets of other links are refused).
    pub link_id: u16,
    /// Our node id, written into the packets we send.
    pub local_node: u8,
    /// The peer's node id: packets from any other (our own reflected back included) are
    /// refused.
    pub peer_node: u8,
    /// Largest forward jump of the peer's counter accepted without a challenge.
    pub max_jump: u64,
    /// Shortest interval between two challenges, ms.
    pub challenge_interval_ms: u64,
}

impl CoreConfig {
    /// A configuration with the default limits.
    pub const fn new(link_id: u16, local_node: u8, peer_node: u8) -> Self {
        Self {
            link_id,
            local_node,
            peer_node,
            max_jump: DEFAULT_MAX_JUMP,
            challenge_interval_ms: DEFAULT_CHALLENGE_INTERVAL_MS,
        }
    }

    /// The host's end of link `link_id`.
    pub const fn host(link_id: u16) -> Self {
        Self::new(link_id, NODE_HOST, NODE_CONTROLLER)
    }

    /// The controller's end of link `link_id`.
    pub const fn controller(link_id: u16) -> Self {
        Self::new(link_id, NODE_CONTROLLER, NODE_HOST)
    }
}

/// Counters of what the link did and what it dropped, and why.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct LinkStats {
    /// Datagrams sent (std endpoint: after fault injection decided nothing; retries included).
    pub sent: u64,
    /// Datagrams received.
    pub received: u64,
    /// Messages delivered to the application.
    pub delivered: u64,
    /// Reliable messages received again (a retry after a lost ack): acknowledged again, not
    /// delivered again.
    pub duplicates: u64,
    /// Acknowledgements sent (duplicates' included).
    pub acks_sent: u64,
    /// Authentic, fresh acknowledgements received.
    pub acks_received: u64,
    /// Retransmissions of reliable messages (std endpoint).
    pub retries: u64,
    /// Reliable sends given up (std endpoint).
    pub timeouts: u64,
    /// Acknowledgements of no message waiting for one (late, after a timeout; std endpoint).
    pub stale_acks: u64,
    /// Received messages dropped because the application did not take them (std endpoint).
    pub inbox_overflows: u64,
    /// Challenges sent.
    pub challenges_sent: u64,
    /// Challenges of the peer answered.
    pub challenge_responses_sent: u64,
    /// Resynchronisations to the peer's epoch and counter (fresh challenge responses).
    pub resyncs: u64,
    /// Not a packet of this format (length, magic, version, flags, kind, payload encoding).
    pub rejected_malformed: u64,
    /// Another message schema.
    pub rejected_schema: u64,
    /// Another link id.
    pub rejected_wrong_link: u64,
    /// Another sender than the peer (our own packets reflected back included).
    pub rejected_wrong_sender: u64,
    /// Unsigned while signing is configured.
    pub rejected_unsigned: u64,
    /// Signed while the link is configured unsigned.
    pub rejected_unexpected_tag: u64,
    /// Tag does not verify.
    pub rejected_bad_tag: u64,
    /// Counter already accepted or below the window: replayed, or duplicated by the network
    /// (the two are indistinguishable).
    pub rejected_replay: u64,
    /// Counter more than the jump limit ahead (a challenge follows).
    pub rejected_future: u64,
    /// Authentic, but from an epoch we are not synchronised to (a challenge follows).
    pub rejected_unsynced: u64,
    /// Challenge responses to no outstanding challenge.
    pub rejected_stale_response: u64,
    /// Packets of epoch 0 (reserved: no sender uses it).
    pub rejected_zero_epoch: u64,
    /// Authentic `Stop`s delivered although a window would have dropped them (replayed, old,
    /// far ahead, of an epoch we are not synchronised to, or a duplicate): a stop always runs.
    pub stops_outside_windows: u64,
    /// Reliable messages whose sequence number lay more than the window below the highest one
    /// delivered (only a peer with broken state sends them): delivered, and the sequence
    /// window restarted at them, so a wrong sequence number never silences the peer.
    pub sequence_resyncs: u64,
}

impl LinkStats {
    /// All rejections added up.
    pub fn rejected(&self) -> u64 {
        self.rejected_malformed
            + self.rejected_schema
            + self.rejected_wrong_link
            + self.rejected_wrong_sender
            + self.rejected_unsigned
            + self.rejected_unexpected_tag
            + self.rejected_bad_tag
            + self.rejected_replay
            + self.rejected_future
            + self.rejected_unsynced
            + self.rejected_stale_response
            + self.rejected_zero_epoch
    }
}

/// Why a datagram was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Reject {
    /// Not a valid packet.
    Malformed(DecodeError),
    /// Another schema hash.
    Schema,
    /// Another link id.
    WrongLink,
    /// Another sender id.
    WrongSender,
    /// No tag, signing configured.
    Unsigned,
    /// A tag, signing not configured.
    UnexpectedTag,
    /// Tag does not verify.
    BadTag,
    /// Counter replayed or too old.
    Replay,
    /// Counter too far ahead.
    TooFarAhead,
    /// Epoch not synchronised.
    Unsynced,
    /// Response to no outstanding challenge.
    StaleResponse,
    /// Epoch 0, which no sender uses.
    ZeroEpoch,
}

impl fmt::Display for Reject {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Reject::Malformed(e) => write!(f, "malformed: {e}"),
            Reject::Schema => f.write_str("other message schema"),
            Reject::WrongLink => f.write_str("other link id"),
            Reject::WrongSender => f.write_str("other sender"),
            Reject::Unsigned => f.write_str("unsigned"),
            Reject::UnexpectedTag => f.write_str("signed, link unsigned"),
            Reject::BadTag => f.write_str("bad tag"),
            Reject::Replay => f.write_str("replayed or duplicated counter"),
            Reject::TooFarAhead => f.write_str("counter too far ahead"),
            Reject::Unsynced => f.write_str("epoch not synchronised"),
            Reject::StaleResponse => f.write_str("stale challenge response"),
            Reject::ZeroEpoch => f.write_str("epoch 0 (reserved)"),
        }
    }
}

/// What a received datagram amounted to.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Event {
    /// A new message for the application.
    Message {
        /// Its header (sequence number, epoch, counter, whether it was reliable).
        header: Header,
        /// The message.
        message: Message,
    },
    /// A reliable message already delivered (its ack is in the reply).
    Duplicate {
        /// Its sequence number.
        seq: u32,
    },
    /// The peer acknowledged our message `seq`.
    Acked {
        /// The acknowledged sequence number.
        seq: u32,
    },
    /// The peer challenged us (the response is in the reply).
    Challenged,
    /// A fresh response to our challenge: we accept the peer's packets from this epoch and
    /// counter on.
    Synced {
        /// The peer's epoch.
        epoch: u32,
        /// The counter of its response.
        counter: u64,
    },
    /// Dropped.
    Rejected(Reject),
}

/// The outcome of [`LinkCore::receive`].
#[derive(Clone, Debug, PartialEq)]
pub struct Incoming {
    /// What happened.
    pub event: Event,
    /// Bytes written at the start of the reply buffer, to send to the peer (an ack or a
    /// challenge response).
    pub reply: Option<usize>,
}

/// A packet encoded for sending.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sent {
    /// Its length.
    pub len: usize,
    /// Its sequence number.
    pub seq: u32,
    /// Its counter.
    pub counter: u64,
}

/// Why a [`LinkCore`] cannot be made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ConfigError {
    /// The local and peer node ids are equal (a reflected packet would be accepted).
    SameNodeIds,
    /// Epoch 0 is reserved.
    ZeroEpoch,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ConfigError::SameNodeIds => "local and peer node ids must differ",
            ConfigError::ZeroEpoch => "epoch 0 is reserved",
        })
    }
}

impl core::error::Error for ConfigError {}

#[derive(Clone, Copy, Debug)]
struct PeerState {
    epoch: u32,
    window: ReplayWindow,
    /// Sequence numbers of the reliable messages delivered (duplicate suppression).
    reliable: ReplayWindow,
}

#[derive(Clone, Copy, Debug)]
struct Outstanding {
    counter: u64,
}

/// One end of a link: our epoch, counter and sequence numbers, the peer's replay state, and the
/// challenge in flight. See the crate docs for the protocol it implements.
pub struct LinkCore {
    config: CoreConfig,
    signer: Option<Signer>,
    epoch: u32,
    counter: u64,
    seq: u32,
    peer: Option<PeerState>,
    wants_challenge: bool,
    challenge: Option<Outstanding>,
    /// When the last challenge left (answered or not): challenges are at least
    /// [`CoreConfig::challenge_interval_ms`] apart, whatever the peer does.
    last_challenge_ms: Option<u64>,
    stats: LinkStats,
}

impl fmt::Debug for LinkCore {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LinkCore")
            .field("config", &self.config)
            .field("signed", &self.signer.is_some())
            .field("epoch", &self.epoch)
            .field("counter", &self.counter)
            .field("peer_epoch", &self.peer.map(|p| p.epoch))
            .finish_non_exhaustive()
    }
}

impl LinkCore {
    /// A link end that signs with `signer` (`None`: unsigned, no authentication at all) and
    /// sends in `epoch`, which must never have been used before with this key, node and link
    /// (see the crate docs, "Restarts").
    pub fn new(
        config: CoreConfig,
        signer: Option<Signer>,
        epoch: u32,
    ) -> Result<Self, ConfigError> {
        if config.local_node == config.peer_node {
            return Err(ConfigError::SameNodeIds);
        }
        if epoch == 0 {
            return Err(ConfigError::ZeroEpoch);
        }
        Ok(Self {
            config,
            signer,
            epoch,
            counter: 0,
            seq: 0,
            peer: None,
            wants_challenge: true,
            challenge: None,
            last_challenge_ms: None,
            stats: LinkStats::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CoreConfig {
        &self.config
    }

    /// Our epoch.
    pub fn epoch(&self) -> u32 {
        self.epoch
    }

    /// The last counter we used (0: none yet).
    pub fn counter(&self) -> u64 {
        self.counter
    }

    /// Whether packets are signed.
    pub fn is_signed(&self) -> bool {
        self.signer.is_some()
    }

    /// The peer's epoch we accept packets of, once synchronised.
    pub fn peer_epoch(&self) -> Option<u32> {
        self.peer.map(|p| p.epoch)
    }

    /// The counters.
    pub fn stats(&self) -> &LinkStats {
        &self.stats
    }

    /// The counters, for the endpoint that drives this core.
    pub fn stats_mut(&mut self) -> &mut LinkStats {
        &mut self.stats
    }

    fn next_counter(&mut self) -> Result<u64, EncodeError> {
        if self.counter == u64::MAX {
            return Err(EncodeError::Exhausted);
        }
        self.counter += 1;
        Ok(self.counter)
    }

    fn header(&self, counter: u64, seq: u32, ack_requested: bool) -> Header {
        Header {
            ack_requested,
            sender: self.config.local_node,
            link_id: self.config.link_id,
            schema: SCHEMA_HASH,
            epoch: self.epoch,
            counter,
            seq,
        }
    }

    /// Encodes `message` under a new sequence number and counter into `out` (give it
    /// [`wire::MAX_DATAGRAM`] bytes). `reliable`: the peer must acknowledge it.
    pub fn encode_message(
        &mut self,
        message: &Message,
        reliable: bool,
        out: &mut [u8],
    ) -> Result<Sent, EncodeError> {
        let seq = self.seq.checked_add(1).ok_or(EncodeError::Exhausted)?;
        let counter = self.next_counter()?;
        let header = self.header(counter, seq, reliable);
        let len = wire::encode(
            &header,
            &Body::Data(message.clone()),
            self.signer.as_ref(),
            out,
        )?;
        self.seq = seq;
        Ok(Sent { len, seq, counter })
    }

    /// Gives the encoded packet `datagram` (one of ours) a new counter and a new tag: a retry,
    /// signed at send time. Returns the new counter.
    pub fn resign(&mut self, datagram: &mut [u8]) -> Result<u64, EncodeError> {
        let counter = self.next_counter()?;
        wire::resign(datagram, counter, self.signer.as_ref())
            .map_err(|_| EncodeError::BadControl)?;
        Ok(counter)
    }

    fn encode_control(&mut self, body: &Body, seq: u32, out: &mut [u8]) -> Option<usize> {
        let counter = self.next_counter().ok()?;
        let header = self.header(counter, seq, false);
        wire::encode(&header, body, self.signer.as_ref(), out).ok()
    }

    /// Whether we accept the peer's packets (a fresh challenge response has been received).
    pub fn is_synced(&self) -> bool {
        self.peer.is_some()
    }

    /// Writes a challenge into `out` when one is needed (not synchronised, or the peer's
    /// authentic packets came from another epoch or too far ahead) and none was sent in the
    /// last [`CoreConfig::challenge_interval_ms`] (answered or not: a flood of replayed
    /// old-epoch packets gets at most one challenge per interval). Call it after each
    /// [`LinkCore::receive`] and periodically; `now_ms` is any monotonic clock in ms.
    pub fn poll_challenge(&mut self, now_ms: u64, out: &mut [u8]) -> Option<usize> {
        if !self.wants_challenge {
            return None;
        }
        if self
            .last_challenge_ms
            .is_some_and(|t| now_ms.saturating_sub(t) < self.config.challenge_interval_ms)
        {
            return None;
        }
        let counter = self.counter.checked_add(1)?;
        let len = self.encode_control(&Body::Challenge, 0, out)?;
        self.challenge = Some(Outstanding { counter });
        self.last_challenge_ms = Some(now_ms);
        self.stats.challenges_sent += 1;
        Some(len)
    }

    fn reject(&mut self, r: Reject) -> Incoming {
        let s = &mut self.stats;
        match r {
            Reject::Malformed(_) => s.rejected_malformed += 1,
            Reject::Schema => s.rejected_schema += 1,
            Reject::WrongLink => s.rejected_wrong_link += 1,
            Reject::WrongSender => s.rejected_wrong_sender += 1,
            Reject::Unsigned => s.rejected_unsigned += 1,
            Reject::UnexpectedTag => s.rejected_unexpected_tag += 1,
            Reject::BadTag => s.rejected_bad_tag += 1,
            Reject::Replay => s.rejected_replay += 1,
            Reject::TooFarAhead => s.rejected_future += 1,
            Reject::Unsynced => s.rejected_unsynced += 1,
            Reject::StaleResponse => s.rejected_stale_response += 1,
            Reject::ZeroEpoch => s.rejected_zero_epoch += 1,
        }
        Incoming {
            event: Event::Rejected(r),
            reply: None,
        }
    }

    /// The replay verdict on a data or ack packet's epoch and counter (`None`: not
    /// synchronised to that epoch).
    fn verdict(&self, h: &Header) -> Option<Verdict> {
        match self.peer {
            Some(p) if p.epoch == h.epoch => Some(p.window.check(h.counter, self.config.max_jump)),
            _ => None,
        }
    }

    /// Processes one received datagram. A reply (ack or challenge response), if any, is
    /// written to `reply` (give it [`wire::MAX_DATAGRAM`] bytes) and must be sent to the
    /// configured peer address, never to the datagram's source. Call
    /// [`LinkCore::poll_challenge`] afterwards.
    ///
    /// Order of the checks: layout; schema, link, sender and epoch; signed or not; the replay
    /// window (read only, so a replay costs no HMAC); the tag; synchronisation and jump limit;
    /// the payload; then the window is updated. Nothing that fails a check changes any state.
    /// An authentic `Stop` is the exception to the windows: it is delivered whatever they say
    /// (see [`Self::receive_stop`]).
    pub fn receive(&mut self, datagram: &[u8], reply: &mut [u8]) -> Incoming {
        self.stats.received += 1;
        let p = match wire::parse(datagram) {
            Ok(p) => p,
            Err(e) => return self.reject(Reject::Malformed(e)),
        };
        if let Err(r) = self.check_addressing(&p) {
            return self.reject(r);
        }
        let h = p.header;
        let stop = p.kind == Kind::Data && p.payload == STOP_PAYLOAD;
        let verdict = match p.kind {
            Kind::Data | Kind::Ack => self.verdict(&h),
            Kind::Challenge | Kind::Response => None,
        };
        if !stop && matches!(verdict, Some(Verdict::Replay | Verdict::TooOld)) {
            return self.reject(Reject::Replay);
        }
        if let Some(s) = &self.signer {
            if !p.verify(s) {
                return self.reject(Reject::BadTag);
            }
        }
        // Authentic from here on.
        match p.kind {
            Kind::Challenge => self.receive_challenge(&h, reply),
            Kind::Response => self.receive_response(&p),
            Kind::Data if stop => self.receive_stop(h, verdict, reply),
            Kind::Data | Kind::Ack => self.receive_data_or_ack(&p, verdict, reply),
        }
    }

    /// Steps 2–5 of the receive order: schema, link, sender, epoch 0, signed or not.
    fn check_addressing(&self, p: &wire::Parsed<'_>) -> Result<(), Reject> {
        let h = &p.header;
        if h.schema != SCHEMA_HASH {
            return Err(Reject::Schema);
        }
        if h.link_id != self.config.link_id {
            return Err(Reject::WrongLink);
        }
        if h.sender != self.config.peer_node {
            return Err(Reject::WrongSender);
        }
        if h.epoch == 0 {
            return Err(Reject::ZeroEpoch);
        }
        match (&self.signer, p.signed) {
            (Some(_), false) => Err(Reject::Unsigned),
            (None, true) => Err(Reject::UnexpectedTag),
            _ => Ok(()),
        }
    }

    fn receive_challenge(&mut self, h: &Header, reply: &mut [u8]) -> Incoming {
        if self.peer.is_none() {
            self.wants_challenge = true;
        }
        let echo = Body::Response {
            epoch: h.epoch,
            counter: h.counter,
        };
        let len = self.encode_control(&echo, 0, reply);
        if len.is_some() {
            self.stats.challenge_responses_sent += 1;
        }
        Incoming {
            event: Event::Challenged,
            reply: len,
        }
    }

    fn receive_response(&mut self, p: &wire::Parsed<'_>) -> Incoming {
        let h = p.header;
        let Ok(Body::Response { epoch, counter }) = p.body() else {
            return self.reject(Reject::Malformed(DecodeError::BadControl));
        };
        match self.challenge {
            Some(o) if epoch == self.epoch && counter == o.counter => {}
            _ => return self.reject(Reject::StaleResponse),
        }
        self.challenge = None;
        self.wants_challenge = false;
        match &mut self.peer {
            Some(ps) if ps.epoch == h.epoch => {
                // Same epoch: only ever forward (a counter above the window top was
                // never accepted, so the counters between stay acceptable once).
                if ps.window.check(h.counter, u64::MAX) == Verdict::Fresh {
                    ps.window.accept(h.counter);
                }
            }
            _ => {
                self.peer = Some(PeerState {
                    epoch: h.epoch,
                    window: ReplayWindow::starting_at(h.counter),
                    reliable: ReplayWindow::new(),
                });
            }
        }
        self.stats.resyncs += 1;
        Incoming {
            event: Event::Synced {
                epoch: h.epoch,
                counter: h.counter,
            },
            reply: None,
        }
    }

    /// An authentic `Stop`: delivered (and acknowledged when asked) whatever the replay window,
    /// the synchronisation and the sequence window say. Stopping twice is harmless and a
    /// replayed stop can do no more than a dropped packet can (stop the arm), while a stop
    /// dropped by a window whose state a faulty peer corrupted would leave the arm moving. Only
    /// a fresh counter of the synchronised epoch moves the windows, as for any packet.
    fn receive_stop(&mut self, h: Header, verdict: Option<Verdict>, reply: &mut [u8]) -> Incoming {
        let in_windows = match (self.peer.as_mut(), verdict) {
            (Some(peer), Some(Verdict::Fresh)) => {
                peer.window.accept(h.counter);
                !h.ack_requested || peer.reliable.record_sequence(u64::from(h.seq)).is_some()
            }
            (_, Some(Verdict::Replay | Verdict::TooOld)) => false,
            _ => {
                // Unsynchronised or far ahead: as for any packet, resynchronise.
                self.wants_challenge = true;
                false
            }
        };
        if !in_windows {
            self.stats.stops_outside_windows += 1;
        }
        let ack = if h.ack_requested {
            self.encode_control(&Body::Ack, h.seq, reply)
        } else {
            None
        };
        if ack.is_some() {
            self.stats.acks_sent += 1;
        }
        self.stats.delivered += 1;
        Incoming {
            event: Event::Message {
                header: h,
                message: Message::Stop,
            },
            reply: ack,
        }
    }

    fn receive_data_or_ack(
        &mut self,
        p: &wire::Parsed<'_>,
        verdict: Option<Verdict>,
        reply: &mut [u8],
    ) -> Incoming {
        let h = p.header;
        match verdict {
            None => {
                self.wants_challenge = true;
                return self.reject(Reject::Unsynced);
            }
            Some(Verdict::TooFarAhead) => {
                self.wants_challenge = true;
                return self.reject(Reject::TooFarAhead);
            }
            _ => {}
        }
        let message = match p.kind {
            Kind::Data => match p.body() {
                Ok(Body::Data(m)) => Some(m),
                Ok(_) => None,
                Err(e) => return self.reject(Reject::Malformed(e)),
            },
            _ => None,
        };
        let Some(peer) = self.peer.as_mut() else {
            return self.reject(Reject::Unsynced);
        };
        peer.window.accept(h.counter);
        let Some(message) = message else {
            self.stats.acks_received += 1;
            return Incoming {
                event: Event::Acked { seq: h.seq },
                reply: None,
            };
        };
        if !h.ack_requested {
            self.stats.delivered += 1;
            return Incoming {
                event: Event::Message { header: h, message },
                reply: None,
            };
        }
        let recorded = peer.reliable.record_sequence(u64::from(h.seq));
        if recorded == Some(Verdict::TooOld) {
            self.stats.sequence_resyncs += 1;
        }
        let fresh = recorded.is_some();
        let ack = self.encode_control(&Body::Ack, h.seq, reply);
        if ack.is_some() {
            self.stats.acks_sent += 1;
        }
        if fresh {
            self.stats.delivered += 1;
            Incoming {
                event: Event::Message { header: h, message },
                reply: ack,
            }
        } else {
            self.stats.duplicates += 1;
            Incoming {
                event: Event::Duplicate { seq: h.seq },
                reply: ack,
            }
        }
    }
}

/// The payload of a `Stop` message (its variant index, nothing else).
const STOP_PAYLOAD: &[u8] = &[3];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::auth::Key;
    use crate::wire::MAX_DATAGRAM;

    fn pair() -> (LinkCore, LinkCore) {
        let key = Key::from_bytes(&[0x42; 32]).expect("key");
        let h = LinkCore::new(CoreConfig::host(7), Some(Signer::new(&key)), 10).expect("core");
        let c =
            LinkCore::new(CoreConfig::controller(7), Some(Signer::new(&key)), 20).expect("core");
        (h, c)
    }

    /// `x` challenges `y` and takes its response.
    fn challenge(x: &mut LinkCore, y: &mut LinkCore) {
        let mut buf = [0u8; MAX_DATAGRAM];
        let mut reply = [0u8; MAX_DATAGRAM];
        let mut reply2 = [0u8; MAX_DATAGRAM];
        let n = x.poll_challenge(0, &mut buf).expect("challenge");
        let r = y.receive(&buf[..n], &mut reply);
        assert_eq!(r.event, Event::Challenged);
        let m = r.reply.expect("response");
        let s = x.receive(&reply[..m], &mut reply2);
        assert!(matches!(s.event, Event::Synced { .. }), "{s:?}");
    }

    fn sync(a: &mut LinkCore, b: &mut LinkCore) {
        challenge(a, b);
        challenge(b, a);
    }

    #[test]
    fn messages_flow_after_the_challenges() {
        let (mut h, mut c) = pair();
        let mut buf = [0u8; MAX_DATAGRAM];
        let mut reply = [0u8; MAX_DATAGRAM];
        let sent = h
            .encode_message(&Message::Heartbeat, true, &mut buf)
            .expect("encode");
        // Not synchronised yet: dropped, and the controller wants a challenge.
        let r = c.receive(&buf[..sent.len], &mut reply);
        assert_eq!(r.event, Event::Rejected(Reject::Unsynced));
        sync(&mut h, &mut c);
        h.resign(&mut buf[..sent.len]).expect("resign");
        let r = c.receive(&buf[..sent.len], &mut reply);
        assert!(matches!(r.event, Event::Message { .. }), "{r:?}");
        let ack = r.reply.expect("ack");
        let mut reply2 = [0u8; MAX_DATAGRAM];
        let a = h.receive(&reply[..ack], &mut reply2);
        assert_eq!(a.event, Event::Acked { seq: sent.seq });
        // The same datagram again: a replay.
        let r = c.receive(&buf[..sent.len], &mut reply);
        assert_eq!(r.event, Event::Rejected(Reject::Replay));
        // Re-signed (a retry): a duplicate, acknowledged again, not delivered.
        h.resign(&mut buf[..sent.len]).expect("resign");
        let r = c.receive(&buf[..sent.len], &mut reply);
        assert_eq!(r.event, Event::Duplicate { seq: sent.seq });
        assert!(r.reply.is_some());
        assert_eq!(c.stats().delivered, 1);
    }

    #[test]
    fn equal_node_ids_and_epoch_zero_are_refused() {
        assert_eq!(
            LinkCore::new(CoreConfig::new(1, 3, 3), None, 1).err(),
            Some(ConfigError::SameNodeIds)
        );
        assert_eq!(
            LinkCore::new(CoreConfig::host(1), None, 0).err(),
            Some(ConfigError::ZeroEpoch)
        );
    }
}
