//! Fault injection on the send path of an endpoint: loss, duplication, reordering and delay,
//! from a seeded generator (reproducible) or a rule per packet.

use std::boxed::Box;
use std::fmt;
use std::io;
use std::time::{Duration, Instant};
use std::vec::Vec;

use crate::wire::{self, Kind};

/// Random faults, each packet drawn independently (in this order: drop, duplicate, reorder,
/// then delay for the rest).
#[derive(Clone, Debug, PartialEq)]
pub struct FaultConfig {
    /// Probability that a packet is not sent.
    pub drop: f64,
    /// Probability that a packet is sent twice.
    pub duplicate: f64,
    /// Probability that a packet is held back and sent after the next one (or after
    /// `reorder_hold`, whichever is first).
    pub reorder: f64,
    /// Longest hold of a reordered packet.
    pub reorder_hold: Duration,
    /// Fixed delay of every packet not dropped or held.
    pub delay: Duration,
    /// Extra random delay, uniform in `0..jitter` (delays larger than the packet spacing
    /// reorder packets too).
    pub jitter: Duration,
    /// Seed of the generator.
    pub seed: u64,
}

impl Default for FaultConfig {
    fn default() -> Self {
        Self {
            drop: 0.0,
            duplicate: 0.0,
            reorder: 0.0,
            reorder_hold: Duration::from_millis(20),
            delay: Duration::ZERO,
            jitter: Duration::ZERO,
            seed: 1,
        }
    }
}

/// What happens to one packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    /// Sent now.
    Send,
    /// Not sent.
    Drop,
    /// Sent twice now.
    Duplicate,
    /// Sent after the next packet (or after `reorder_hold`).
    Hold,
    /// Sent after this delay.
    Delay(Duration),
}

/// What a rule sees of a packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PacketInfo {
    /// Index of the packet among those this injector has seen (from 0).
    pub index: u64,
    /// Its kind.
    pub kind: Kind,
    /// Its sequence number.
    pub seq: u32,
    /// Its counter.
    pub counter: u64,
    /// Whether it asks for an ack.
    pub ack_requested: bool,
}

/// What the injector did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaultStats {
    /// Packets submitted.
    pub seen: u64,
    /// Dropped.
    pub dropped: u64,
    /// Sent twice.
    pub duplicated: u64,
    /// Held back and sent after a later one.
    pub reordered: u64,
    /// Delayed.
    pub delayed: u64,
}

type Rule = Box<dyn FnMut(&PacketInfo) -> Option<Fate> + Send>;

/// Faults on an endpoint's send path ([`crate::LinkEndpoint::set_fault_injector`]). A rule, if
/// set, decides a packet's fate first; when it returns `None` the random faults of the
/// [`FaultConfig`] decide.
pub struct FaultInjector {
    config: FaultConfig,
    state: u64,
    rule: Option<Rule>,
    /// (release time, held for reordering, bytes), in submission order.
    queue: Vec<(Instant, bool, Vec<u8>)>,
    stats: FaultStats,
}

impl fmt::Debug for FaultInjector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FaultInjector")
            .field("config", &self.config)
            .field("rule", &self.rule.is_some())
            .field("queued", &self.queue.len())
            .field("stats", &self.stats)
            .finish()
    }
}

impl FaultInjector {
    /// Random faults only.
    pub fn new(config: FaultConfig) -> Self {
        Self {
            state: config.seed,
            config,
            rule: None,
            queue: Vec::new(),
            stats: FaultStats::default(),
        }
    }

    /// No random faults; `rule` decides each packet (`None`: sent).
    pub fn with_rule(rule: impl FnMut(&PacketInfo) -> Option<Fate> + Send + 'static) -> Self {
        Self::new(FaultConfig::default()).rule(rule)
    }

    /// Adds a rule in front of the random faults.
    pub fn rule(mut self, rule: impl FnMut(&PacketInfo) -> Option<Fate> + Send + 'static) -> Self {
        self.rule = Some(Box::new(rule));
        self
    }

    /// What it did so far.
    pub fn stats(&self) -> FaultStats {
        self.stats
    }

    /// splitmix64.
    fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn fate(&mut self, info: &PacketInfo) -> Fate {
        if let Some(rule) = self.rule.as_mut() {
            if let Some(f) = rule(info) {
                return f;
            }
        }
        let c = &self.config;
        let (drop, dup, reorder) = (c.drop, c.duplicate, c.reorder);
        let (delay, jitter) = (c.delay, c.jitter);
        let r = self.unit();
        if r < drop {
            Fate::Drop
        } else if r < drop + dup {
            Fate::Duplicate
        } else if r < drop + dup + reorder {
            Fate::Hold
        } else if delay > Duration::ZERO || jitter > Duration::ZERO {
            let extra = jitter.mul_f64(self.unit());
            Fate::Delay(delay + extra)
        } else {
            Fate::Send
        }
    }

    /// Submits one packet; `send` puts bytes on the wire.
    pub(crate) fn submit(
        &mut self,
        bytes: &[u8],
        now: Instant,
        mut send: impl FnMut(&[u8]) -> io::Result<()>,
    ) -> io::Result<()> {
        let info = match wire::parse(bytes) {
            Ok(p) => PacketInfo {
                index: self.stats.seen,
                kind: p.kind,
                seq: p.header.seq,
                counter: p.header.counter,
                ack_requested: p.header.ack_requested,
            },
            Err(_) => PacketInfo {
                index: self.stats.seen,
                kind: Kind::Data,
                seq: 0,
                counter: 0,
                ack_requested: false,
            },
        };
        self.stats.seen += 1;
        let fate = self.fate(&info);
        match fate {
            Fate::Drop => {
                self.stats.dropped += 1;
                return Ok(());
            }
            Fate::Hold => {
                self.stats.reordered += 1;
                self.queue
                    .push((now + self.config.reorder_hold, true, bytes.to_vec()));
                return Ok(());
            }
            Fate::Delay(d) => {
                self.stats.delayed += 1;
                self.queue.push((now + d, false, bytes.to_vec()));
            }
            Fate::Send => send(bytes)?,
            Fate::Duplicate => {
                self.stats.duplicated += 1;
                send(bytes)?;
                send(bytes)?;
            }
        }
        // Packets held for reordering go out after this one.
        let mut i = 0;
        while i < self.queue.len() {
            if self.queue[i].1 {
                let (_, _, b) = self.queue.remove(i);
                send(&b)?;
            } else {
                i += 1;
            }
        }
        Ok(())
    }

    /// Sends the queued packets whose time has come.
    pub(crate) fn release_due(
        &mut self,
        now: Instant,
        mut send: impl FnMut(&[u8]) -> io::Result<()>,
    ) -> io::Result<()> {
        let mut i = 0;
        while i < self.queue.len() {
            if self.queue[i].0 <= now {
                let (_, _, b) = self.queue.remove(i);
                send(&b)?;
            } else {
                i += 1;
            }
        }
        Ok(())
    }

    /// When the next queued packet is due.
    pub(crate) fn next_due(&self) -> Option<Instant> {
        self.queue.iter().map(|q| q.0).min()
    }
}
