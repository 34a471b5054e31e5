//! The manipulator controller: what answers the robot over the link, for any arm.
//!
//! * [`command`], [`limits`]: every value a command carries, checked once (finite, in range, in
//!   time) into a [`command::Checked`] before anything moves; refusals name the field.
//! * [`arm`]: the arm interface ([`Arm`]): limits, clock, checked commands in, state out.
//! * [`server`]: the link side over any [`Arm`]: commands, refusals, the 100 Hz state stream, a
//!   watchdog, and fault injection (packet loss/delay/reordering/duplication, sensor stalls,
//!   restarts).
//! * [`sim`] (feature `sim`): the simulated arm and finger over a scene, its sensor behind the
//!   real firmware code streaming 400 Hz frames into a pseudo-terminal.
//!
//! The binary `crackbot-controller` (`--arm sim`) runs it as its own process; the mission
//! library starts the simulated one in-process for the no-argument mission.

pub mod arm;
pub mod command;
pub mod limits;
pub mod motion;
pub mod ros2;
pub mod server;
#[cfg(feature = "sim")]
pub mod sim;

pub use arm::{Arm, ArmState, Mode};
pub use command::{check, Checked, CommandError};
pub use limits::{Limits, Refusal};
pub use server::{ControllerError, Faults, LinkServer, LinkSettings, SensorStall, ServerReport};
#[cfg(feature = "sim")]
pub use sim::sensor::{Shared, SharedWorld, SimSensor};
#[cfg(feature = "sim")]
pub use sim::world::{Tick, World};
#[cfg(feature = "sim")]
pub use sim::{ServerConfig, SimArm, SimController};
/// The controller's clock as its state stream reports it: the world's ticks (1/400 s of
/// simulated time each, `1/(400·speedup)` s of wall time), shifted by `offset_us` and running
/// `drift_ppm` fast, so the robot's clock synchronisation is tested against a known truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerClock {
    /// Wall-clock speed-up of the simulation (1: real time).
    pub speedup: f64,
    /// Offset of the controller's clock, µs.
    pub offset_us: f64,
    /// Rate error of the controller's clock, parts per million.
    pub drift_ppm: f64,
}

impl Default for ControllerClock {
    fn default() -> Self {
        ControllerClock {
            speedup: 1.0,
            offset_us: 0.0,
            drift_ppm: 0.0,
        }
    }
}

impl ControllerClock {
    /// The controller's time at world tick `tick`, µs.
    pub fn at_tick(&self, tick: u64) -> u64 {
        let wall_us = tick as f64 * 2500.0 / self.speedup;
        (wall_us * (1.0 + self.drift_ppm * 1e-6) + self.offset_us).max(0.0) as u64
    }
}
