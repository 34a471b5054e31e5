//! The rig layer: what a mission runs on, as the steps above it use it.
//!
//! * where the arm, sensor and camera are ([`RigBackend`]: [`HardwareRig`], or the simulated
//!   rig behind the cargo feature `sim`), started by `start.rs`, at a [`Site`];
//! * the arm over the link (`arm.rs`) and the sensor stream (`sensor.rs`) on the host's clock;
//! * the runtime context a step gets (`context.rs`: the arm, the sensor, the camera, the stop
//!   flag and the front end, and the pump that keeps the streams flowing), with the passes it
//!   can command: a slide recorded (`slide.rs`) and a raised pass recorded (`hover.rs`);
//! * what is shown and kept while it runs: the streams as they arrive (`live.rs`), the running
//!   verdict (`feel.rs`), the log (`log.rs`) and each pass's CSV (`recording.rs`);
//! * its sections of the configuration ([`RigConfig`], [`OutputConfig`], [`Hardware`]).
//!
//! Nothing here decides about cracks: the steps (`super::steps`) do, over this layer.

pub(crate) mod arm;
pub(crate) mod backend;
pub(crate) mod context;
pub(crate) mod feel;
pub(crate) mod hover;
pub(crate) mod live;
pub(crate) mod log;
pub(crate) mod recording;
#[cfg(feature = "ros2")]
pub(crate) mod ros2;
pub(crate) mod sensor;
pub(crate) mod settings;
#[cfg(feature = "sim")]
pub(crate) mod simulated;
pub(crate) mod site;
pub(crate) mod slide;
pub(crate) mod start;
