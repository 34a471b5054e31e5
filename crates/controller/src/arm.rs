//! The arm interface: what the link side ([`crate::server`]) needs of an arm, whichever arm it is.
//!
//! The link side checks every command ([`crate::command::check`]) against the arm's
//! [`Limits`], hands the checked command to the arm, streams the arm's [`ArmState`] and reports
//! the slides it finished. Two arms implement it: the simulated one (`sim` feature,
//! [`crate::sim::SimArm`]) and a ROS 2 arm over DDS (`ros2` feature, `crate::ros2`).

use std::time::Duration;

use serde::Serialize;

use crate::command::Checked;
use crate::limits::{Limits, Refusal};

/// What the arm is doing (the link's mode without its fault, which [`Arm::fault`] reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Mode {
    /// Standing still, ready.
    Idle,
    /// Travelling (finger lifted).
    Moving,
    /// Travelling to, or sliding along, slide `id`.
    Sliding(u32),
    /// Stopped by a `Stop` (or the watchdog); the next command clears it.
    Stopped,
}

impl Mode {
    /// The link's mode.
    pub fn to_link(self) -> crackbot_link::Mode {
        match self {
            Mode::Idle => crackbot_link::Mode::Idle,
            Mode::Moving => crackbot_link::Mode::Moving,
            Mode::Sliding(id) => crackbot_link::Mode::Sliding { id },
            Mode::Stopped => crackbot_link::Mode::Stopped,
        }
    }
}

/// The arm's state as the link streams it, in the surface frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmState {
    /// The controller's clock when the state was measured, µs.
    pub time_us: u64,
    /// Finger tip, mm `[x, y, z]` (z: height above the plate, 0 in contact).
    pub pose: [f64; 3],
    /// Velocity, mm/s.
    pub velocity: [f64; 3],
    /// What the arm does.
    pub mode: Mode,
    /// Fraction of the current slide done, 0–1.
    pub progress: f64,
}

/// An arm the link side can drive.
///
/// Every method returns at once (the link side calls them from its loop, which must keep its
/// 100 Hz state stream and its watchdog): an arm that talks to hardware does so from its own
/// thread and answers here from what it last heard.
pub trait Arm: Send {
    /// The limits every command is checked against before [`Arm::apply`] sees it.
    fn limits(&self) -> Limits;
    /// The controller's clock now, µs (the clock of [`ArmState::time_us`] and of commands'
    /// deadlines).
    fn now_us(&self) -> u64;
    /// Starts a checked command, replacing what the arm was doing; `Some(id)`: slide `id`
    /// started. A refusal means nothing moved.
    fn apply(&mut self, command: Checked) -> Result<Option<u32>, Refusal>;
    /// Stops where it is, at once. Never fails: a stop always stops.
    fn stop(&mut self);
    /// Whether the arm is busy with a command (the watchdog stops only a busy arm).
    fn is_busy(&self) -> bool;
    /// The newest state, `None` before the arm has reported one.
    fn state(&self) -> Option<ArmState>;
    /// Slides finished since the last call.
    fn take_finished(&mut self) -> Vec<u32>;
    /// A fault that stopped the arm (`Mode::Fault { code }` on the link), with its reason.
    fn fault(&self) -> Option<(u16, String)>;
    /// Fault injection: silence the simulated sensor for `d`. Arms without one ignore it.
    fn stall_sensor(&mut self, d: Duration) {
        let _ = d;
    }
}
