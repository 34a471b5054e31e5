//! Mission commands: what a station asks of a robot, signed with the link's pre-shared key.
//!
//! A command travels as the payload of a Zenoh query on `crackbot/<robot>/command`:
//!
//! ```text
//! payload = flag (1 byte: 0 unsigned, 1 signed) ‖ body ‖ tag (16 bytes, signed only)
//! body    = postcard(CommandRequest { version, robot, station, epoch_unix_ms, counter,
//!                                     sent_unix_ms, command })
//! tag     = HMAC-SHA256(key, "crackbot-telemetry-command-v1\0" ‖ body)[..16]
//! ```
//!
//! The key and the HMAC are the link's ([`crackbot_link::Signer`]); the domain string keeps a
//! link datagram from ever verifying as a command and the other way round. The robot answers
//! with one reply, `postcard(CommandReply)`.
//!
//! What the robot checks ([`CommandGuard`]), in this order:
//! 1. the payload decodes and speaks [`crate::wire::WIRE_VERSION`];
//! 2. it is addressed to this robot (a command recorded for one robot is refused by another);
//! 3. commands that move or stop an arm ([`Command::needs_key`]) must be signed, the robot must
//!    have a key (a robot without one can be watched, never commanded), and the tag must verify;
//! 4. it was sent within [`FRESHNESS_MS`] of the robot's clock, and not before the robot
//!    started: a command recorded before a restart is refused after it, and a timestamp far in
//!    the future is refused instead of being stored (it cannot lock the real station out);
//! 5. per station: an older `epoch` (the station's start time) is refused, a newer one starts a
//!    new anti-replay window, and inside an epoch the counter passes the link's sliding window
//!    ([`crackbot_link::ReplayWindow`]): a reordered command is accepted once, a replay never.
//!
//! The state changes only after every check has passed. [`Command::EmergencyStop`] is accepted
//! from anyone, signed or not (safety before availability: any station that can see a robot can
//! halt its arm); everything else needs the key. A signed [`Command::Stop`] skips steps 4 and 5
//! (it runs even when replayed, late, from an older epoch or far ahead of the window, without
//! moving the window): a stop must never be lost to a window's state, and a replayed one can do
//! no more than stop the mission.
//!
//! Not protected: confidentiality (telemetry and commands travel in clear; run Zenoh over TLS or
//! a VPN where that matters), denial of service (a flood of queries, or of emergency stops),
//! and the telemetry itself, which is not signed (a peer on the network can publish under a
//! robot's key expression; restrict that with Zenoh's access control on a site router).

use std::collections::HashMap;

use crackbot_link::{Key, ReplayWindow, Signer, Verdict, DEFAULT_MAX_JUMP, TAG_LEN};
use serde::{Deserialize, Serialize};

use crate::wire::WIRE_VERSION;

/// Domain separation of command tags from link tags.
pub const DOMAIN: &[u8] = b"crackbot-telemetry-command-v1\0";

/// How far a command's send time may be from the robot's clock, ms.
pub const FRESHNESS_MS: u64 = 30_000;

/// What a station can ask.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// Start a mission (the robot must be idle and serving).
    Start {
        /// `tactile`, `vision` or `fused`.
        mode: String,
        /// A scene file's TOML (`None`: the robot's own scene).
        scene_toml: Option<String>,
    },
    /// Stop the running mission: the arm stops first, then the mission ends with what it has.
    Stop,
    /// Stop the arm now, from anyone.
    EmergencyStop,
}

impl Command {
    /// Whether only a station with the key may send it.
    pub fn needs_key(&self) -> bool {
        !matches!(self, Command::EmergencyStop)
    }

    /// Its name, for logs and replies.
    pub fn name(&self) -> &'static str {
        match self {
            Command::Start { .. } => "start",
            Command::Stop => "stop",
            Command::EmergencyStop => "emergency stop",
        }
    }
}

/// The signed part of a command.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CommandRequest {
    /// [`WIRE_VERSION`].
    pub version: u16,
    /// The robot it is for.
    pub robot: String,
    /// The sending station's random id.
    pub station: u64,
    /// When that station started, ms since the Unix epoch (its epoch).
    pub epoch_unix_ms: u64,
    /// The station's counter in that epoch, from 1.
    pub counter: u64,
    /// When it was sent, ms since the Unix epoch.
    pub sent_unix_ms: u64,
    /// The command.
    pub command: Command,
}

/// The robot's answer.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum CommandReply {
    /// Accepted: the robot acts on it.
    Accepted,
    /// Refused, with the reason.
    Refused(String),
}

/// Milliseconds since the Unix epoch.
pub fn unix_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

/// A station's side: numbers and signs its commands.
#[derive(Debug)]
pub struct CommandSigner {
    signer: Option<Signer>,
    station: u64,
    epoch_unix_ms: u64,
    counter: u64,
}

impl CommandSigner {
    /// A station with `key` (`None`: it can only send unsigned commands, which robots refuse
    /// except the emergency stop).
    pub fn new(key: Option<&Key>) -> Self {
        CommandSigner {
            signer: key.map(Signer::new),
            station: rand::random(),
            epoch_unix_ms: unix_ms(),
            counter: 0,
        }
    }

    /// Whether it has a key.
    pub fn has_key(&self) -> bool {
        self.signer.is_some()
    }

    /// The query payload of `command` for `robot`: signed when there is a key.
    pub fn encode(&mut self, robot: &str, command: Command) -> Vec<u8> {
        self.counter += 1;
        let request = CommandRequest {
            version: WIRE_VERSION,
            robot: robot.to_string(),
            station: self.station,
            epoch_unix_ms: self.epoch_unix_ms,
            counter: self.counter,
            sent_unix_ms: unix_ms(),
            command,
        };
        let body = postcard::to_allocvec(&request).unwrap_or_default();
        let mut out = Vec::with_capacity(1 + body.len() + TAG_LEN);
        match &self.signer {
            Some(s) => {
                out.push(1);
                out.extend_from_slice(&body);
                out.extend_from_slice(&s.tag(&signed_bytes(&body)));
            }
            None => {
                out.push(0);
                out.extend_from_slice(&body);
            }
        }
        out
    }
}

fn signed_bytes(body: &[u8]) -> Vec<u8> {
    let mut v = Vec::with_capacity(DOMAIN.len() + body.len());
    v.extend_from_slice(DOMAIN);
    v.extend_from_slice(body);
    v
}

/// Per station: its epoch and the counters accepted in it.
#[derive(Debug, Clone, Copy)]
struct StationState {
    epoch_unix_ms: u64,
    window: ReplayWindow,
}

/// The robot's side: decides on each command (see the module docs for the checks).
#[derive(Debug)]
pub struct CommandGuard {
    robot: String,
    signer: Option<Signer>,
    started_unix_ms: u64,
    stations: HashMap<u64, StationState>,
}

/// Why a command was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Refusal {
    /// Not a command.
    #[error("malformed command: {0}")]
    Malformed(String),
    /// Another wire version.
    #[error("command of wire version {0} (this robot speaks {WIRE_VERSION})")]
    Version(u16),
    /// For another robot.
    #[error("command addressed to robot {0:?}, not this one")]
    WrongRobot(String),
    /// Unsigned, and it needs the key.
    #[error("unsigned {0} command refused: commands that move or stop the arm must be signed with the link key")]
    Unsigned(&'static str),
    /// The robot has no key.
    #[error("this robot has no command key: it can be watched, not commanded")]
    NoKey,
    /// The tag does not verify.
    #[error("the command's signature does not verify (wrong key or altered command)")]
    BadTag,
    /// Sent too long ago, before the robot started, or in the future.
    #[error("stale or future command: sent {0} ms from this robot's clock (or before it started); clocks must agree within 30 s")]
    NotFresh(i64),
    /// An older epoch of the station.
    #[error("command from an earlier run of its station")]
    OldEpoch,
    /// Already accepted, or too old for the window.
    #[error("replayed command (counter {0} already seen or too old)")]
    Replay(u64),
    /// The counter jumped too far ahead.
    #[error("command counter {0} jumps too far ahead")]
    TooFarAhead(u64),
}

impl CommandGuard {
    /// The guard of `robot`, with the link key (`None`: only emergency stops are accepted).
    pub fn new(robot: &str, key: Option<&Key>) -> Self {
        CommandGuard {
            robot: robot.to_string(),
            signer: key.map(Signer::new),
            started_unix_ms: unix_ms(),
            stations: HashMap::new(),
        }
    }

    /// The command in `payload`, if every check passes (at `now_unix_ms`).
    pub fn check(&mut self, payload: &[u8], now_unix_ms: u64) -> Result<Command, Refusal> {
        let (&flag, rest) = payload
            .split_first()
            .ok_or_else(|| Refusal::Malformed("empty payload".into()))?;
        let (body, tag) = match flag {
            0 => (rest, None),
            1 if rest.len() > TAG_LEN => {
                let (b, t) = rest.split_at(rest.len() - TAG_LEN);
                (b, Some(t))
            }
            1 => {
                return Err(Refusal::Malformed(
                    "signed command shorter than its tag".into(),
                ))
            }
            f => return Err(Refusal::Malformed(format!("unknown flag byte {f}"))),
        };
        let (version, _) = postcard::take_from_bytes::<u16>(body)
            .map_err(|e| Refusal::Malformed(e.to_string()))?;
        if version != WIRE_VERSION {
            return Err(Refusal::Version(version));
        }
        let request: CommandRequest =
            postcard::from_bytes(body).map_err(|e| Refusal::Malformed(e.to_string()))?;
        if request.robot != self.robot {
            return Err(Refusal::WrongRobot(request.robot));
        }
        if !request.command.needs_key() {
            return Ok(request.command);
        }
        let Some(tag) = tag else {
            return Err(Refusal::Unsigned(request.command.name()));
        };
        let signer = self.signer.as_ref().ok_or(Refusal::NoKey)?;
        if !signer.verify(&signed_bytes(body), tag) {
            return Err(Refusal::BadTag);
        }
        match self.check_fresh(&request, now_unix_ms) {
            Ok(state) => {
                self.stations.insert(request.station, state);
                Ok(request.command)
            }
            // A signed stop runs whatever the clocks and windows say (it is still signed):
            // stopping twice is harmless, and a stop refused by a station's corrupted window or
            // a skewed clock would leave the mission running.
            Err(
                Refusal::NotFresh(_)
                | Refusal::OldEpoch
                | Refusal::Replay(_)
                | Refusal::TooFarAhead(_),
            ) if request.command == Command::Stop => Ok(Command::Stop),
            Err(e) => Err(e),
        }
    }

    /// Steps 4 and 5: the send time, the station's epoch and its counter window. Returns the
    /// station's state with the counter accepted (stored by the caller).
    fn check_fresh(
        &self,
        request: &CommandRequest,
        now_unix_ms: u64,
    ) -> Result<StationState, Refusal> {
        let skew = request.sent_unix_ms as i64 - now_unix_ms as i64;
        if skew.unsigned_abs() > FRESHNESS_MS || request.sent_unix_ms < self.started_unix_ms {
            return Err(Refusal::NotFresh(skew));
        }
        let mut state = match self.stations.get(&request.station) {
            Some(s) if request.epoch_unix_ms < s.epoch_unix_ms => return Err(Refusal::OldEpoch),
            Some(s) if request.epoch_unix_ms == s.epoch_unix_ms => *s,
            _ => StationState {
                epoch_unix_ms: request.epoch_unix_ms,
                window: ReplayWindow::new(),
            },
        };
        match state.window.check(request.counter, DEFAULT_MAX_JUMP) {
            Verdict::Fresh => {}
            Verdict::Replay | Verdict::TooOld => return Err(Refusal::Replay(request.counter)),
            Verdict::TooFarAhead => return Err(Refusal::TooFarAhead(request.counter)),
        }
        state.window.accept(request.counter);
        Ok(state)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(b: u8) -> Key {
        Key::from_bytes(&[b; 32]).unwrap()
    }

    fn start() -> Command {
        Command::Start {
            mode: "fused".into(),
            scene_toml: None,
        }
    }

    #[test]
    fn a_signed_command_is_accepted_once_and_its_replay_never() {
        let mut station = CommandSigner::new(Some(&key(7)));
        let mut robot = CommandGuard::new("r1", Some(&key(7)));
        let p = station.encode("r1", start());
        assert_eq!(robot.check(&p, unix_ms()), Ok(start()));
        assert!(matches!(
            robot.check(&p, unix_ms()),
            Err(Refusal::Replay(1))
        ));
    }

    #[test]
    fn reordered_commands_are_each_accepted_once() {
        let mut station = CommandSigner::new(Some(&key(7)));
        let mut robot = CommandGuard::new("r1", Some(&key(7)));
        let a = station.encode("r1", start());
        let b = station.encode("r1", start());
        assert!(robot.check(&b, unix_ms()).is_ok());
        assert!(robot.check(&a, unix_ms()).is_ok());
        assert!(robot.check(&a, unix_ms()).is_err());
        assert!(robot.check(&b, unix_ms()).is_err());
    }

    #[test]
    fn unsigned_wrong_key_altered_and_keyless_are_refused_but_an_emergency_stop_is_not() {
        let mut robot = CommandGuard::new("r1", Some(&key(7)));
        let mut anon = CommandSigner::new(None);
        assert!(matches!(
            robot.check(&anon.encode("r1", start()), unix_ms()),
            Err(Refusal::Unsigned("start"))
        ));
        assert!(matches!(
            robot.check(&anon.encode("r1", Command::Stop), unix_ms()),
            Err(Refusal::Unsigned("stop"))
        ));
        assert_eq!(
            robot.check(&anon.encode("r1", Command::EmergencyStop), unix_ms()),
            Ok(Command::EmergencyStop)
        );
        let mut other = CommandSigner::new(Some(&key(8)));
        assert_eq!(
            robot.check(&other.encode("r1", start()), unix_ms()),
            Err(Refusal::BadTag)
        );
        let mut good = CommandSigner::new(Some(&key(7)));
        let mut p = good.encode("r1", start());
        let n = p.len();
        p[n - TAG_LEN - 1] ^= 1; // a bit of the body
        assert!(robot.check(&p, unix_ms()).is_err());
        let p = good.encode("r1", start());
        let mut p2 = p.clone();
        p2[n - 1] ^= 1; // a bit of the tag
        assert_eq!(robot.check(&p2, unix_ms()), Err(Refusal::BadTag));
        // "Signing on but no key" accepts nothing.
        let mut keyless = CommandGuard::new("r1", None);
        assert_eq!(keyless.check(&p, unix_ms()), Err(Refusal::NoKey));
    }

    #[test]
    fn a_command_for_one_robot_is_refused_by_another() {
        let mut station = CommandSigner::new(Some(&key(7)));
        let mut r2 = CommandGuard::new("r2", Some(&key(7)));
        assert_eq!(
            r2.check(&station.encode("r1", start()), unix_ms()),
            Err(Refusal::WrongRobot("r1".into()))
        );
    }

    #[test]
    fn a_command_from_the_future_is_refused_and_does_not_lock_the_station_out() {
        let mut station = CommandSigner::new(Some(&key(7)));
        let mut robot = CommandGuard::new("r1", Some(&key(7)));
        let p = station.encode("r1", start());
        // Seen by a robot whose clock is an hour behind: from the future.
        let now = unix_ms();
        assert!(matches!(
            robot.check(&p, now - 3_600_000),
            Err(Refusal::NotFresh(_))
        ));
        // Nothing was stored: the same command is still accepted on time.
        assert!(robot.check(&p, now).is_ok());
    }

    #[test]
    fn a_command_recorded_before_the_robot_restarted_is_refused_after() {
        let mut station = CommandSigner::new(Some(&key(7)));
        let recorded = station.encode("r1", start());
        std::thread::sleep(std::time::Duration::from_millis(5));
        // The robot restarts: its windows are empty, but the command predates it.
        let mut restarted = CommandGuard::new("r1", Some(&key(7)));
        assert!(matches!(
            restarted.check(&recorded, unix_ms()),
            Err(Refusal::NotFresh(_))
        ));
        // A new command of the same station is accepted.
        assert!(restarted
            .check(&station.encode("r1", start()), unix_ms())
            .is_ok());
    }

    #[test]
    fn an_earlier_run_of_a_station_is_refused() {
        let k = key(7);
        let mut first = CommandSigner::new(Some(&k));
        std::thread::sleep(std::time::Duration::from_millis(3));
        let mut robot = CommandGuard::new("r1", Some(&k));
        let old = first.encode("r1", start());
        let mut second = CommandSigner {
            station: first.station,
            epoch_unix_ms: first.epoch_unix_ms + 1,
            counter: 0,
            signer: Some(Signer::new(&k)),
        };
        assert!(robot
            .check(&second.encode("r1", Command::Stop), unix_ms())
            .is_ok());
        assert_eq!(robot.check(&old, unix_ms()), Err(Refusal::OldEpoch));
    }

    /// A signed stop runs whatever the windows and clocks say, without moving them; unsigned
    /// or wrongly signed, it is refused like any command.
    #[test]
    fn a_signed_stop_runs_when_replayed_late_old_or_far_ahead() {
        let k = key(7);
        let mut station = CommandSigner::new(Some(&k));
        let mut robot = CommandGuard::new("r1", Some(&k));
        let stop = station.encode("r1", Command::Stop);
        let now = unix_ms();
        assert_eq!(robot.check(&stop, now), Ok(Command::Stop));
        // Replayed, an hour late, from the future.
        assert_eq!(robot.check(&stop, now), Ok(Command::Stop));
        assert_eq!(robot.check(&stop, now + 3_600_000), Ok(Command::Stop));
        // Far ahead of the window: a station whose counter state broke.
        let mut jumped = CommandSigner {
            station: station.station,
            epoch_unix_ms: station.epoch_unix_ms,
            counter: 1_000_000,
            signer: Some(Signer::new(&k)),
        };
        assert_eq!(
            robot.check(&jumped.encode("r1", Command::Stop), now),
            Ok(Command::Stop)
        );
        // Nothing moved: the station's next start is still accepted, its replay still not.
        let next = station.encode("r1", start());
        assert_eq!(robot.check(&next, now), Ok(start()));
        assert!(matches!(robot.check(&next, now), Err(Refusal::Replay(_))));
        let mut stranger = CommandSigner::new(Some(&key(8)));
        assert_eq!(
            robot.check(&stranger.encode("r1", Command::Stop), now),
            Err(Refusal::BadTag)
        );
    }

    #[test]
    fn garbage_is_named_not_panicked_on() {
        let mut robot = CommandGuard::new("r1", Some(&key(7)));
        for p in [&[][..], &[9, 1, 2], &[1, 0, 0], &[0, 0xff, 0xff, 0xff]] {
            assert!(robot.check(p, unix_ms()).is_err(), "{p:?}");
        }
        let mut p = CommandSigner::new(None).encode("r1", Command::Stop);
        p[1] = 9; // wire version 9
        assert_eq!(robot.check(&p, unix_ms()), Err(Refusal::Version(9)));
    }
}
