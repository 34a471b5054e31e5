//! One session of the rig for a commissioning step: the backend the configuration names
//! started, the arm over the link and the sensor stream awaited, the step run, and everything
//! stopped and shut down whatever the step returned (the arm told to stop first on an error).

use std::path::Path;
use std::sync::atomic::AtomicBool;

use crate::inspect::rig::context::Rig;
use crate::inspect::rig::start::{rig_of, start};
use crate::inspect::steps::wait::wait_for_streams;
use crate::inspect::{InspectMode, Progress, RigConfig};
use crate::MissionError;

/// Runs `step` on the rig `config` names, its link's state and recordings under `out_dir`;
/// `stop` ends it (the arm is stopped). The step's own errors come back as they are.
pub(crate) fn on_rig<T, E: From<MissionError>>(
    config: &RigConfig,
    out_dir: &Path,
    stop: &AtomicBool,
    step: impl FnOnce(&mut Rig<'_>) -> Result<T, E>,
) -> Result<T, E> {
    let mode = InspectMode::Tactile;
    let mut backend = rig_of(config, mode)?;
    std::fs::create_dir_all(out_dir).map_err(|e| crate::error::io_err(out_dir, e))?;
    let (mut arm, mut sensor) = match start(config, mode, out_dir, backend.as_mut()) {
        Ok(parts) => parts,
        Err(e) => {
            backend.shutdown();
            return Err(E::from(e));
        }
    };
    let result = {
        let mut quiet = |_: &Progress| {};
        let mut rig = Rig::new(
            (config, out_dir),
            &mut arm,
            &mut sensor,
            backend.as_mut(),
            stop,
            &mut quiet,
        );
        wait_for_streams(&mut rig)
            .map_err(E::from)
            .and_then(|()| step(&mut rig))
    };
    if result.is_err() {
        arm.stop();
    }
    drop(sensor);
    backend.shutdown();
    result
}
