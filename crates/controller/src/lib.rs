//! The simulated manipulator controller: what answers the robot over the link when there is no
//! arm.
//!
//! * [`command`]: every value a command carries, checked once (finite, in range, in time)
//!   into a [`command::Checked`] before anything moves; refusals name the field.
//! * [`world`]: the arm and the finger over a scene (`crackbot-sim`), stepped one sensor sample
//!   at a time, refusing any motion outside its workspace or speed limits whoever asks.
//! * [`sensor`]: the simulated sensor behind the real firmware code, streaming 400 Hz frames into
//!   a pseudo-terminal, so the robot reads it exactly as it reads the board.
//! * [`server`]: the link side: commands, refusals, the 100 Hz state stream, a watchdog, and
//!   fault injection (packet loss/delay/reordering/duplication, sensor stalls, restarts).
//!
//! The binary `crackbot-sim-controller` runs it as its own process; the mission library starts
//! it in-process for the no-argument mission.

pub mod command;
pub mod limits;
pub mod sensor;
pub mod server;
pub mod world;

pub use command::{check, Checked, CommandError};
pub use limits::{Limits, Refusal};
pub use sensor::{Shared, SharedWorld, SimSensor};
pub use server::{ControllerError, Faults, SensorStall, ServerConfig, ServerReport, SimController};
pub use world::{Mode, Tick, World};

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
