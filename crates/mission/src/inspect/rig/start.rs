//! Starting the rig: the backend a configuration names ([`rig_of`]), then the arm over the
//! authenticated link and the sensor stream, wherever that backend says they are.

use std::collections::VecDeque;
use std::path::Path;
use std::time::Instant;

use crackbot_link::{EpochSource, LinkConfig, LinkEndpoint, Security};

use super::arm::Arm;
use super::backend::{HardwareRig, RigBackend};
use super::sensor::Sensor;
use super::settings::RigConfig;
use crate::error::{io_err, link_err};
use crate::inspect::report::InspectMode;
use crate::sync::ClockSync;
use crate::MissionError;

/// The arm over the authenticated link and the sensor stream of the rig `backend` (its state
/// files under `out_dir/.link/`); `mode` is named in errors.
pub(crate) fn start(
    config: &RigConfig,
    mode: InspectMode,
    out_dir: &Path,
    backend: &mut dyn RigBackend,
) -> Result<(Arm, Sensor), MissionError> {
    let state_dir = out_dir.join(".link");
    std::fs::create_dir_all(&state_dir).map_err(|e| io_err(&state_dir, e))?;
    let c = backend.connect(config, mode, &state_dir)?;
    let t0 = Instant::now();
    let mut ep = LinkEndpoint::from_socket(
        c.socket,
        c.controller,
        LinkConfig::host(
            Security::Signed(c.key),
            EpochSource::File(state_dir.join("host.epoch")),
        ),
    )
    .map_err(|e| link_err("opening the link", e))?;
    if let Some(f) = &config.host_link_faults {
        ep.set_fault_injector(Some(crackbot_link::FaultInjector::new(f.clone())));
    }
    let arm = Arm {
        ep,
        sync: ClockSync::new(30e6),
        t0,
        states: VecDeque::new(),
        done: Vec::new(),
        errors: Vec::new(),
        last_heartbeat: Instant::now(),
        last_state_at: None,
        epoch: None,
        restarted: false,
    };
    let sensor = Sensor::open(&c.sensor_port, t0)?;
    Ok((arm, sensor))
}

/// The rig `config` names: its hardware, or the simulated rig of its scene (feature `sim`);
/// `mode` is named in errors.
#[cfg_attr(
    feature = "sim",
    expect(
        unused_variables,
        reason = "only a build without the simulator names the mode in its error"
    )
)]
pub fn rig_of(config: &RigConfig, mode: InspectMode) -> Result<Box<dyn RigBackend>, MissionError> {
    match &config.hardware {
        Some(hw) => Ok(Box::new(HardwareRig::new(hw.clone()))),
        #[cfg(feature = "sim")]
        None => Ok(Box::new(super::simulated::SimulatedRig::default())),
        #[cfg(not(feature = "sim"))]
        None => Err(MissionError::Missing {
            mode: mode.as_str(),
            what: "hardware (--serial, --controller and --key): this build has no simulator \
                   (the cargo feature `sim` is off)",
        }),
    }
}
