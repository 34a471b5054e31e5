//! The first step: the arm's state stream and the sensor's samples arrive, or the mission ends
//! naming the one that stayed silent.

use std::time::{Duration, Instant};

use crate::inspect::rig::context::Rig;
use crate::MissionError;

/// How long the arm's state stream and the sensor have to start, s.
const STREAMS_START_S: u64 = 5;

/// Waits for the arm's state stream and the sensor ([`STREAMS_START_S`]); an error names the
/// one that stayed silent.
pub(crate) fn wait_for_streams(rig: &mut Rig<'_>) -> Result<(), MissionError> {
    let deadline = Instant::now() + Duration::from_secs(STREAMS_START_S);
    while rig.arm.states.is_empty() || rig.sensor.samples.is_empty() {
        rig.pump(Duration::from_millis(5))?;
        if Instant::now() > deadline {
            return Err(if rig.arm.states.is_empty() {
                MissionError::ControllerUnreachable {
                    addr: rig.arm.ep.peer_addr().to_string(),
                }
            } else {
                MissionError::NoSamples {
                    port: rig.sensor.path.clone(),
                }
            });
        }
    }
    Ok(())
}
