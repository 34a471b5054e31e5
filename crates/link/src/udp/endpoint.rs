//! The UDP endpoint: a [`LinkCore`] over a `std::net::UdpSocket`, with acknowledgements,
//! retries, timeouts and an inbox.

use std::boxed::Box;
use std::collections::VecDeque;
use std::fmt;
use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use super::epoch::{EpochError, EpochFile};
use super::fault::FaultInjector;
use super::key_file::KeyFileError;
use crate::auth::{Key, Signer};
use crate::message::Message;
use crate::session::{ConfigError, CoreConfig, Event, LinkCore, LinkStats};
use crate::wire::{EncodeError, MAX_DATAGRAM};

/// Whether packets are signed.
#[derive(Clone, Debug)]
pub enum Security {
    /// HMAC-SHA256-128 with this pre-shared key: unsigned, wrongly signed, replayed packets are
    /// refused. The only mode for a robot.
    Signed(Key),
    /// No tag and no authentication at all: anyone who can send a datagram to the port
    /// commands the manipulator. For benchmarks (the unsigned baseline) and tests only.
    UnsignedInsecure,
}

/// Where this endpoint's epoch comes from.
#[derive(Clone, Debug)]
pub enum EpochSource {
    /// The next epoch of this [`EpochFile`] path (the deployed setting: see the crate docs,
    /// "Restarts").
    File(PathBuf),
    /// This epoch, which the caller guarantees was never used before with this key, node and
    /// link (a controller with its own boot counter; tests).
    Fixed(u32),
}

/// The endpoint's configuration.
#[derive(Clone, Debug)]
pub struct LinkConfig {
    /// Signed or not.
    pub security: Security,
    /// The epoch.
    pub epoch: EpochSource,
    /// Link id, node ids, replay limits.
    pub core: CoreConfig,
    /// How long [`LinkEndpoint::send_reliable`] waits for the ack of one attempt.
    pub ack_timeout: Duration,
    /// Attempts of a reliable send (the first included) before [`LinkError::Timeout`].
    pub max_attempts: u32,
    /// Messages received and not yet taken by [`LinkEndpoint::recv`] (the oldest is dropped
    /// beyond it).
    pub inbox_capacity: usize,
}

impl LinkConfig {
    /// Defaults: 50 ms ack timeout, 5 attempts, inbox of 4096 messages.
    pub fn new(core: CoreConfig, security: Security, epoch: EpochSource) -> Self {
        Self {
            security,
            epoch,
            core,
            ack_timeout: Duration::from_millis(50),
            max_attempts: 5,
            inbox_capacity: 4096,
        }
    }

    /// The host's end of link 1.
    pub fn host(security: Security, epoch: EpochSource) -> Self {
        Self::new(CoreConfig::host(1), security, epoch)
    }

    /// The controller's end of link 1.
    pub fn controller(security: Security, epoch: EpochSource) -> Self {
        Self::new(CoreConfig::controller(1), security, epoch)
    }

    /// The same with link id `link_id`.
    pub fn with_link_id(mut self, link_id: u16) -> Self {
        self.core.link_id = link_id;
        self
    }
}

/// Errors of the endpoint.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinkError {
    /// The socket failed.
    #[error("link socket: {0}")]
    Io(#[from] io::Error),
    /// A reliable message was not acknowledged after `attempts` attempts.
    #[error("no acknowledgement from {peer} after {attempts} attempts")]
    Timeout {
        /// The peer address.
        peer: SocketAddr,
        /// Attempts made.
        attempts: u32,
    },
    /// The key file was refused.
    #[error("{0}")]
    KeyFile(#[from] KeyFileError),
    /// The epoch file failed.
    #[error("{0}")]
    Epoch(#[from] EpochError),
    /// Inconsistent configuration.
    #[error("link configuration: {0}")]
    Config(#[from] ConfigError),
    /// The message could not be encoded.
    #[error("encoding a message: {0}")]
    Encode(#[from] EncodeError),
}

/// A message delivered by [`LinkEndpoint::recv`]: authentic (when signed), not a replay, not a
/// duplicate of a reliable message already delivered.
#[derive(Clone, Debug, PartialEq)]
pub struct Received {
    /// The message.
    pub message: Message,
    /// Its sequence number (refer to it in [`crate::ErrorReport::seq`]).
    pub seq: u32,
    /// Whether the sender asked for an acknowledgement (sent already).
    pub reliable: bool,
    /// The sender's epoch.
    pub peer_epoch: u32,
    /// The packet's counter.
    pub counter: u64,
    /// Source address of the datagram (not authenticated; replies go to the configured peer).
    pub from: SocketAddr,
    /// When it was received.
    pub at: Instant,
}

/// What one turn of the receive loop produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wake {
    /// Nothing arrived.
    Idle,
    /// A datagram was processed.
    Other,
    /// A message went into the inbox.
    Delivered,
    /// The awaited acknowledgement.
    Acked,
    /// The peer challenged us.
    Challenged,
}

/// Sends `bytes` to `peer`, through the fault injector if there is one.
fn emit(
    socket: &UdpSocket,
    peer: SocketAddr,
    faults: &mut Option<FaultInjector>,
    stats: &mut LinkStats,
    bytes: &[u8],
) -> io::Result<()> {
    stats.sent += 1;
    let send = |b: &[u8]| socket.send_to(b, peer).map(|_| ());
    match faults {
        None => send(bytes),
        Some(f) => f.submit(bytes, Instant::now(), send),
    }
}

/// One end of the link over UDP. Single-threaded: every call drives the protocol (answers
/// challenges, acknowledges, releases delayed packets), so call [`LinkEndpoint::recv`] often
/// (the controller at its loop rate, the host in its receive loop). Messages that arrive while
/// [`LinkEndpoint::send_reliable`] waits for its ack go into the inbox for the next `recv`.
pub struct LinkEndpoint {
    socket: UdpSocket,
    local: SocketAddr,
    peer: SocketAddr,
    core: LinkCore,
    ack_timeout: Duration,
    max_attempts: u32,
    inbox_capacity: usize,
    started: Instant,
    inbox: VecDeque<Received>,
    faults: Option<FaultInjector>,
    nonblocking: bool,
    rx: Box<[u8; 2048]>,
    tx: [u8; MAX_DATAGRAM],
    reply: [u8; MAX_DATAGRAM],
}

impl fmt::Debug for LinkEndpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LinkEndpoint")
            .field("local", &self.local)
            .field("peer", &self.peer)
            .field("core", &self.core)
            .finish_non_exhaustive()
    }
}

impl LinkEndpoint {
    /// Binds a UDP socket to `local` and talks to `peer`.
    pub fn bind(
        local: SocketAddr,
        peer: SocketAddr,
        config: LinkConfig,
    ) -> Result<Self, LinkError> {
        Self::from_socket(UdpSocket::bind(local)?, peer, config)
    }

    /// Talks to `peer` over an already bound socket (which it owns from now on; it is not
    /// `connect`ed, so that the source address plays no part: authenticity comes from the tag).
    /// Takes a new epoch (writing the epoch file) and sends a first challenge to the peer.
    pub fn from_socket(
        socket: UdpSocket,
        peer: SocketAddr,
        config: LinkConfig,
    ) -> Result<Self, LinkError> {
        let LinkConfig {
            security,
            epoch,
            core,
            ack_timeout,
            max_attempts,
            inbox_capacity,
        } = config;
        let epoch = match epoch {
            EpochSource::File(path) => EpochFile::new(path).advance()?,
            EpochSource::Fixed(e) => e,
        };
        let signer = match &security {
            Security::Signed(key) => Some(Signer::new(key)),
            Security::UnsignedInsecure => None,
        };
        let core = LinkCore::new(core, signer, epoch)?;
        let local = socket.local_addr()?;
        let mut ep = Self {
            socket,
            local,
            peer,
            core,
            ack_timeout,
            max_attempts: max_attempts.max(1),
            inbox_capacity: inbox_capacity.max(1),
            started: Instant::now(),
            inbox: VecDeque::new(),
            faults: None,
            nonblocking: false,
            rx: Box::new([0; 2048]),
            tx: [0; MAX_DATAGRAM],
            reply: [0; MAX_DATAGRAM],
        };
        ep.poll_challenge()?;
        Ok(ep)
    }

    /// The bound address.
    pub fn local_addr(&self) -> SocketAddr {
        self.local
    }

    /// The peer address every packet goes to.
    pub fn peer_addr(&self) -> SocketAddr {
        self.peer
    }

    /// Our epoch.
    pub fn epoch(&self) -> u32 {
        self.core.epoch()
    }

    /// The last counter we used.
    pub fn counter(&self) -> u64 {
        self.core.counter()
    }

    /// The peer epoch we are synchronised to.
    pub fn peer_epoch(&self) -> Option<u32> {
        self.core.peer_epoch()
    }

    /// Whether we accept the peer's packets yet (after its first fresh challenge response).
    pub fn is_synced(&self) -> bool {
        self.core.is_synced()
    }

    /// What the link did and dropped.
    pub fn stats(&self) -> LinkStats {
        *self.core.stats()
    }

    /// Installs (or with `None` removes) a fault injector on the send path; returns the
    /// previous one. Packets it still holds are dropped with it.
    pub fn set_fault_injector(&mut self, faults: Option<FaultInjector>) -> Option<FaultInjector> {
        std::mem::replace(&mut self.faults, faults)
    }

    /// The fault injector, if any.
    pub fn fault_injector(&self) -> Option<&FaultInjector> {
        self.faults.as_ref()
    }

    fn now_ms(&self) -> u64 {
        u64::try_from(self.started.elapsed().as_millis()).unwrap_or(u64::MAX)
    }

    fn poll_challenge(&mut self) -> io::Result<()> {
        let now = self.now_ms();
        if let Some(len) = self.core.poll_challenge(now, &mut self.reply) {
            emit(
                &self.socket,
                self.peer,
                &mut self.faults,
                self.core.stats_mut(),
                &self.reply[..len],
            )?;
        }
        Ok(())
    }

    fn release_due(&mut self) -> io::Result<()> {
        if let Some(f) = self.faults.as_mut() {
            let (socket, peer) = (&self.socket, self.peer);
            f.release_due(Instant::now(), |b| socket.send_to(b, peer).map(|_| ()))?;
        }
        Ok(())
    }

    /// Sends `message` once, with no acknowledgement (the state stream). Returns its sequence
    /// number.
    pub fn send_unreliable(&mut self, message: &Message) -> Result<u32, LinkError> {
        self.release_due()?;
        let sent = self.core.encode_message(message, false, &mut self.tx)?;
        emit(
            &self.socket,
            self.peer,
            &mut self.faults,
            self.core.stats_mut(),
            &self.tx[..sent.len],
        )?;
        Ok(sent.seq)
    }

    /// Sends `message` and waits for its acknowledgement, retrying (each retry with a new
    /// counter and a new tag) every `ack_timeout`, and at once when the peer challenges us
    /// (it dropped the packet while resynchronising), up to `max_attempts` attempts. Returns
    /// the message's sequence number, or [`LinkError::Timeout`]. Messages received meanwhile
    /// wait in the inbox.
    pub fn send_reliable(&mut self, message: &Message) -> Result<u32, LinkError> {
        self.release_due()?;
        let sent = self.core.encode_message(message, true, &mut self.tx)?;
        let len = sent.len;
        emit(
            &self.socket,
            self.peer,
            &mut self.faults,
            self.core.stats_mut(),
            &self.tx[..len],
        )?;
        let mut attempts = 1;
        let mut deadline = Instant::now() + self.ack_timeout;
        loop {
            let wait = deadline.saturating_duration_since(Instant::now());
            let wake = self.pump(wait, Some(sent.seq))?;
            if wake == Wake::Acked {
                return Ok(sent.seq);
            }
            let retry_now = wake == Wake::Challenged;
            if !retry_now && Instant::now() < deadline {
                continue;
            }
            if attempts >= self.max_attempts {
                if retry_now {
                    // The last attempt still has its time to be acknowledged.
                    if Instant::now() < deadline {
                        continue;
                    }
                }
                self.core.stats_mut().timeouts += 1;
                return Err(LinkError::Timeout {
                    peer: self.peer,
                    attempts,
                });
            }
            self.core.resign(&mut self.tx[..len])?;
            self.core.stats_mut().retries += 1;
            emit(
                &self.socket,
                self.peer,
                &mut self.faults,
                self.core.stats_mut(),
                &self.tx[..len],
            )?;
            attempts += 1;
            deadline = Instant::now() + self.ack_timeout;
        }
    }

    /// The next message, waiting up to `timeout` (`Duration::ZERO`: only what has arrived).
    /// Only authentic, fresh, first copies are delivered; everything else is counted in
    /// [`LinkEndpoint::stats`] and dropped.
    pub fn recv(&mut self, timeout: Duration) -> Result<Option<Received>, LinkError> {
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(r) = self.inbox.pop_front() {
                return Ok(Some(r));
            }
            let wait = deadline.saturating_duration_since(Instant::now());
            let wake = self.pump(wait, None)?;
            if wake == Wake::Idle && Instant::now() >= deadline {
                return Ok(None);
            }
        }
    }

    /// Processes what has arrived without waiting (answers challenges, acknowledges, fills the
    /// inbox, releases delayed packets); returns the number of messages in the inbox.
    pub fn poll(&mut self) -> Result<usize, LinkError> {
        while self.pump(Duration::ZERO, None)? != Wake::Idle {}
        Ok(self.inbox.len())
    }

    fn set_wait(&mut self, wait: Duration) -> io::Result<()> {
        if wait.is_zero() {
            if !self.nonblocking {
                self.socket.set_nonblocking(true)?;
                self.nonblocking = true;
            }
        } else {
            if self.nonblocking {
                self.socket.set_nonblocking(false)?;
                self.nonblocking = false;
            }
            self.socket.set_read_timeout(Some(wait))?;
        }
        Ok(())
    }

    /// Waits up to `wait` for one datagram and processes it.
    fn pump(&mut self, wait: Duration, awaiting: Option<u32>) -> Result<Wake, LinkError> {
        self.release_due()?;
        let mut wait = wait;
        if let Some(due) = self.faults.as_ref().and_then(FaultInjector::next_due) {
            wait = wait.min(due.saturating_duration_since(Instant::now()));
        }
        self.set_wait(wait)?;
        let (n, from) = match self.socket.recv_from(&mut self.rx[..]) {
            Ok(x) => x,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock
                        | io::ErrorKind::TimedOut
                        | io::ErrorKind::Interrupted
                ) =>
            {
                return Ok(Wake::Idle)
            }
            // An ICMP error of an earlier send (the peer's port closed), on platforms that
            // report them on unconnected sockets: not this datagram's fault.
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::ConnectionRefused | io::ErrorKind::ConnectionReset
                ) =>
            {
                return Ok(Wake::Other)
            }
            Err(e) => return Err(e.into()),
        };
        let at = Instant::now();
        let incoming = self.core.receive(&self.rx[..n], &mut self.reply);
        if let Some(len) = incoming.reply {
            emit(
                &self.socket,
                self.peer,
                &mut self.faults,
                self.core.stats_mut(),
                &self.reply[..len],
            )?;
        }
        self.poll_challenge()?;
        Ok(match incoming.event {
            Event::Message { header, message } => {
                if self.inbox.len() >= self.inbox_capacity {
                    self.inbox.pop_front();
                    self.core.stats_mut().inbox_overflows += 1;
                }
                self.inbox.push_back(Received {
                    message,
                    seq: header.seq,
                    reliable: header.ack_requested,
                    peer_epoch: header.epoch,
                    counter: header.counter,
                    from,
                    at,
                });
                Wake::Delivered
            }
            Event::Acked { seq } if Some(seq) == awaiting => Wake::Acked,
            Event::Acked { .. } => {
                self.core.stats_mut().stale_acks += 1;
                Wake::Other
            }
            Event::Challenged => Wake::Challenged,
            _ => Wake::Other,
        })
    }
}
