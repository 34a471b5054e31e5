//! Fleet telemetry over Zenoh: robots publish what they see, feel and decide; stations watch
//! every robot they can reach and send them signed mission commands.
//!
//! Zenoh (the data plane ROS 2 uses through rmw_zenoh) carries everything: an inspection team
//! runs several robots and more than one station, and a home-made socket protocol for that
//! would be the wrong road. This crate is the only one that depends on it (≈270 crates): the
//! headless robot builds without it unless its `telemetry` feature is on.
//!
//! * [`keys`]: the key expressions, `crackbot/<robot>/{tactile,camera,detections,plan,verdicts,
//!   health,mission}` (put), `…/state` and `…/command` (queryables), `…/alive` (liveliness).
//! * [`wire`]: one postcard-encoded [`wire::Envelope`] per sample, versioned.
//! * [`command`]: start, stop and emergency-stop commands, signed with the link's key and
//!   checked against replays, stale and future timestamps and other robots (its module docs
//!   say what the scheme does and does not protect).
//! * [`RobotService`]: a robot that runs missions and publishes them (serving, it takes its
//!   missions from stations); [`RobotNode`]: its Zenoh side; [`Station`]: the station's; [`fleet`]: what a station
//!   knows of each robot, also fed by the operator app from in-process missions and replays.
//!
//! Topology: peer mode on loopback by default. The station listens on
//! [`DEFAULT_STATION_ENDPOINT`] and robots connect there, retrying until it is up; any node can
//! listen or connect elsewhere, and at a site every node is a client of a Zenoh router
//! ([`ZenohOptions::router`]). (Zenoh peers do not relay since 1.9: give them endpoints.)
//!
//! Liveness: a robot's liveliness token disappears when its session closes or its process dies
//! (the TCP link drops), and its heartbeat on `…/health` runs every 200 ms; a station shows it as
//! lost on either sign ([`fleet::LOST_AFTER`]: 1.5 s of silence).

pub mod command;
pub mod fleet;
pub mod keys;
mod robot;
mod service;
mod session;
mod station;
pub mod wire;

pub use command::{Command, CommandReply};
pub use fleet::{Fleet, RobotView};
pub use robot::{CommandHandler, RobotNode, HEARTBEAT_EVERY};
pub use service::{RobotService, StartRequest};
pub use session::{ZenohOptions, DEFAULT_STATION_ENDPOINT};
pub use station::Station;

/// Errors of the telemetry.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TelemetryError {
    /// A setting (endpoint, robot name) is unusable; the message names it.
    #[error("telemetry setting: {0}")]
    Config(String),
    /// The Zenoh session did not open.
    #[error("opening the Zenoh session: {0}")]
    Open(String),
    /// A publisher, subscriber, queryable or token could not be declared.
    #[error("declaring {what}: {detail}")]
    Declare {
        /// What.
        what: String,
        /// Zenoh's reason.
        detail: String,
    },
    /// A put failed.
    #[error("publishing on {key}: {detail}")]
    Publish {
        /// The key expression.
        key: String,
        /// Zenoh's reason.
        detail: String,
    },
    /// A query failed.
    #[error("querying {key}: {detail}")]
    Query {
        /// The key expression.
        key: String,
        /// What went wrong.
        detail: String,
    },
    /// A robot did not answer a command.
    #[error("robot {robot} did not answer within {waited_s:.1} s (not reachable, or not running)")]
    NoAnswer {
        /// The robot.
        robot: String,
        /// How long the station waited.
        waited_s: f64,
    },
    /// A sample could not be encoded or decoded.
    #[error(transparent)]
    Wire(#[from] wire::WireError),
}
