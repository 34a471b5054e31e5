//! The mission library: what an operator runs, as one API that every front end calls.
//!
//! The `crackbot` command line, the headless robot binary and the operator app hold no logic of
//! their own: they turn their inputs (flags, a config file, buttons) into the configurations of
//! this crate, call it, and display the typed, `Serialize` reports it returns. Progress and live
//! data reach them through callbacks; stopping goes in as a future.
//!
//! * [`inspect`]: the inspection mission (tactile, vision or fused) over the authenticated link,
//!   on a rig ([`inspect::RigBackend`]): hardware, or with the cargo feature `sim` (on by
//!   default) the simulated controller and sensor started in-process on a simulated scene.
//! * [`commission`]: a new finger commissioned on the reference plates: its optics, its own
//!   models, a finger profile that missions use.
//! * [`sync`]: passive clock synchronisation of the sensor's and the controller's clocks.
//! * `demo` (feature `sim`): the acquisition demo on a simulated scene: the simulated finger slides across a
//!   crack, the real sensor firmware samples it on this host and streams 400 Hz frames into a new
//!   pseudo-terminal, the acquisition reads them back over the real serial path, records them to
//!   CSV and summarises the stream.
//!
//! Recording a real sensor and replaying recordings are sessions of `crackbot-acquisition`
//! ([`crackbot_acquisition::RecordSession`], [`crackbot_acquisition::session::summarise_replay`]);
//! detection in camera frames is `crackbot-vision`'s.

pub mod commission;
#[cfg(feature = "sim")]
pub mod demo;
mod error;
pub mod inspect;
pub mod sync;

#[cfg(feature = "sim")]
pub use demo::{run_demo, DemoConfig, DemoReport, DemoSurface};
pub use error::MissionError;
pub use inspect::{
    print_check_height, run_inspection, InspectConfig, InspectMode, InspectReport, Progress,
    PRINT_CHECK_HEIGHT_MM, PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_SPEED_MM_S,
};
