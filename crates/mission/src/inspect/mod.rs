//! The inspection mission: look, decide where to touch, slide the finger, classify online,
//! confirm or reject each candidate, report.
//!
//! ```text
//! frame ─▶ detector ─▶ homography (px → mm) ─▶ planner ─▶ link: Slide ─▶ controller ─▶ finger
//!                                                               │
//!   report ◀─ confirm/reject ◀─ deployed tactile model ◀─ samples + positions (clock sync)
//!                                 (online, streaming)          ▲ sensor: serial / PTY
//! ```
//!
//! The same code runs on any rig ([`RigBackend`]): hardware ([`HardwareRig`]: a serial port, a
//! controller address, a camera image) or, with the cargo feature `sim`, a simulated scene,
//! where the simulated rig starts the simulated controller (`crackbot-controller`) in this
//! process: real UDP sockets on loopback, the real firmware code writing into a
//! pseudo-terminal, the real acquisition reading it. What the mission knows of the place is a
//! [`Site`].
//!
//! * **Modes.** `fused` (the default): the detector proposes, the finger confirms. `vision`:
//!   the detector's candidates are the report (nothing is touched). `tactile`: boustrophedon
//!   rows over the whole workspace (the paper's N_s rows for γ), each row classified piece by
//!   piece; the detector is never loaded.
//! * **Print check.** A candidate the finger reads as a crack is passed over once more with the
//!   finger raised (`InspectConfig::print_check_mm`, 2 mm): a print's proximity dip keeps its
//!   share of the signal there, a crack's does not ([`print_check::print_ratio`]; above
//!   [`print_check::PRINT_RATIO`] it is a print). A first ratio within [`PRINT_RATIO_DOUBT`] of
//!   that threshold is measured on [`PRINT_CHECK_PASSES_IN_DOUBT`] raised passes, back and
//!   forth (stopping after two where their mean is settled, [`PRINT_RATIO_SETTLED`]), and the
//!   mean over those passes of each one's print ratio and floor ratio
//!   ([`print_check::floor_ratio`], a second estimate with other errors) decides; every pass is
//!   kept (`raised-NNN.csv`, `raised-NNN-K.csv`). Where the stroke also crossed a second line,
//!   the raised passes are compared with the candidate's own dip ([`own_dip`]), not the
//!   stroke's deepest point. Where the surface at the line stands above the plate (a bump's
//!   flank, [`surface_rise_mm`] beyond [`SURFACE_RISE_TOLERANCE_MM`]), the first raised pass is
//!   made again that much higher (`raised-NNN-again.csv`) and replaces it.
//! * **Pieces of one crack.** The detector may split one crack into several candidates; the
//!   confirmed ones that continue each other ([`PIECE_GAP_MM`]), or whose crossings the crack
//!   map joins ([`PIECE_TRACE_GAP_MM`], [`CrackTrace`]), are reported as one crack.
//! * **Synchronisation.** Sensor samples carry the board's clock, the arm's states the
//!   controller's; both are mapped to the host's clock ([`crate::sync::ClockSync`]) and the arm's
//!   position is interpolated at every sample.
//! * **Faults.** Unacknowledged commands are retried by the link; a slide whose sensor stream
//!   stalled or whose controller restarted is slid again once; a controller that stays
//!   unreachable, or a sensor that stays silent, stops the arm and ends the mission with an
//!   error that says which. Everything recorded up to then is on disk.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crackbot_link::{EpochSource, LinkConfig, LinkEndpoint, Security};
use crackbot_tactile::model::TactileModel;

use crate::sync::ClockSync;
use crate::MissionError;

mod arm;
mod config;
mod feel;
mod judge;
mod live;
mod log;
mod mission;
mod passes;
mod perceive;
mod pieces;
mod raised;
mod report;
mod rig;
mod sensor;
#[cfg(feature = "sim")]
mod simulated;
mod site;
mod touch;

pub use config::{
    doubted_dip_confidence, print_check_height, CandidateSource, Hardware, InspectConfig,
    InspectMode, DOUBTED_DIP_CONFIDENCE, MIN_DIP_COUNTS, PRINT_CHECK_HEIGHT_MM, TOUCH_MARGIN_MM,
    TOUCH_MIN_STROKE_MM,
};
#[cfg(feature = "foxglove")]
pub use crackbot_mcap::DEFAULT_LIVE_ADDR;
pub use feel::Feeling;
pub use judge::{shallowest_crack_ratio, IMPLAUSIBLE_RATIO_SHARE, WEAK_NO_CRACK_CONFIDENCE};
pub use log::LOG_FILE;
pub use passes::{
    own_dip, SEPARATE_DIPS_BACK_SHARE, SEPARATE_DIPS_EXCESS_MM, SEPARATE_DIPS_GAP_MM,
};
pub use pieces::{
    turn_deg, CrackTrace, PIECE_ANGLE_DEG, PIECE_GAP_MM, PIECE_TRACE_GAP_MM, TRACE_REACH_MM,
};
pub use raised::{
    surface_rise_mm, MAX_SURFACE_RISE_MM, PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_PASSES_IN_DOUBT,
    PRINT_CHECK_SPEED_MM_S, PRINT_RATIO_DOUBT, PRINT_RATIO_SETTLED, RAISED_PASS_CLEAR_MM,
    RAISED_PASS_GUARD_COUNTS, SURFACE_RISE_TOLERANCE_MM,
};
pub use report::{
    ArmPose, CrackDoubt, Dip, Evidence, FrameInfo, InspectReport, LinkCounters, LiveSample,
    PassDoubt, PassRecord, Progress, RejectedCandidate, ReportedCrack, StageTimes, StreamHealth,
    StrokeSample, NOT_JUDGED,
};
pub use rig::{rig_of, Connection, HardwareRig, RigBackend};
#[cfg(feature = "sim")]
pub use simulated::SimulatedRig;
pub use site::{ArmLimits, Site};
pub use touch::{RESTROKE_ALONG_MM, RESTROKE_KEEP_MM, UNEVEN_ENDS_SHARE};

use arm::{link_err, Arm};
use passes::Rig;
pub(crate) use perceive::io_err;
use sensor::Sensor;
/// Runs a mission (see the [module docs](self)) on the rig `config` names ([`rig_of`]): its
/// hardware, or the simulated rig of its scene. `stop` ends it early (the arm is stopped
/// first); `progress` sees each stage. The report is also saved as `report.json` in the
/// mission's folder.
pub fn run_inspection(
    config: &InspectConfig,
    stop: &AtomicBool,
    progress: impl FnMut(&Progress),
) -> Result<InspectReport, MissionError> {
    config.check()?;
    let mut rig = rig_of(config)?;
    run_inspection_on(config, rig.as_mut(), stop, progress)
}

/// [`run_inspection`] on a rig of the caller's.
pub fn run_inspection_on(
    config: &InspectConfig,
    backend: &mut dyn RigBackend,
    stop: &AtomicBool,
    mut progress: impl FnMut(&Progress),
) -> Result<InspectReport, MissionError> {
    let started = Instant::now();
    config.check()?;
    progress(&Progress::Starting);
    let recognition = TactileModel::load(&config.recognition_model)?;
    let width = TactileModel::load(&config.width_model)?;
    std::fs::create_dir_all(&config.out_dir).map_err(|e| io_err(&config.out_dir, e))?;
    let started_rig = start_rig(config, backend);
    let (mut arm, mut sensor) = match started_rig {
        Ok(parts) => parts,
        Err(e) => {
            backend.shutdown();
            return Err(e);
        }
    };
    let setup_s = started.elapsed().as_secs_f64();
    let mut log = match log::MissionLog::open(config, arm.t0) {
        Ok(log) => log,
        Err(e) => {
            drop(sensor);
            backend.shutdown();
            return Err(e);
        }
    };
    if let Some(l) = log.as_mut() {
        l.record(&Progress::Starting);
    }
    let result = {
        let mut logged = |p: &Progress| {
            if let Some(l) = log.as_mut() {
                l.record(p);
            }
            progress(p);
        };
        let mut rig = Rig::new(config, &mut arm, &mut sensor, backend, stop, &mut logged);
        mission::mission(&mut rig, (&recognition, &width), started, setup_s)
    };
    if result.is_err() {
        arm.stop();
    }
    let s = arm.ep.stats();
    let counters = LinkCounters {
        sent: s.sent,
        retries: s.retries,
        rejected: s.rejected(),
        duplicates: s.duplicates,
    };
    drop(sensor);
    backend.shutdown();
    let mut report = match result {
        Ok(r) => r,
        Err(e) => {
            if let Some(l) = log {
                // The mission's own error is the one to report; a log that fails too says so.
                if let Err(le) = l.finish(Err(&e)) {
                    tracing::warn!("{le}");
                }
            }
            return Err(e);
        }
    };
    report.link = counters;
    save_report(&config.out_dir.join("report.json"), &report)?;
    if let Some(l) = log {
        l.finish(Ok(&report))?;
    }
    Ok(report)
}

/// Writes the report as pretty JSON.
fn save_report(path: &Path, report: &InspectReport) -> Result<(), MissionError> {
    let json = serde_json::to_string_pretty(report)?;
    std::fs::write(path, json).map_err(|e| io_err(path, e))
}

/// The arm over the authenticated link and the sensor stream of the rig `backend` (its state
/// files under `.link/`).
fn start_rig(
    config: &InspectConfig,
    backend: &mut dyn RigBackend,
) -> Result<(Arm, Sensor), MissionError> {
    let state_dir = config.out_dir.join(".link");
    std::fs::create_dir_all(&state_dir).map_err(|e| io_err(&state_dir, e))?;
    let c = backend.connect(config, &state_dir)?;
    let t0 = Instant::now();
    let mut ep = LinkEndpoint::from_socket(
        c.socket,
        c.controller,
        LinkConfig::host(
            Security::Signed(c.key),
            EpochSource::File(state_dir.join("host.epoch")),
        ),
    )
    .map_err(link_err)?;
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
