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
//!   finger raised ([`PrintCheckConfig::height_mm`], 2 mm): a print's proximity dip keeps its
//!   share of the signal there, a crack's does not ([`crackbot_tactile::print_check::print_ratio`]; above
//!   [`crackbot_tactile::print_check::PRINT_RATIO`] it is a print). A first ratio within [`PRINT_RATIO_DOUBT`] of
//!   that threshold is measured on [`PRINT_CHECK_PASSES_IN_DOUBT`] raised passes, back and
//!   forth (stopping after two where their mean is settled, [`PRINT_RATIO_SETTLED`]), and the
//!   mean over those passes of each one's print ratio and floor ratio
//!   ([`crackbot_tactile::print_check::floor_ratio`], a second estimate with other errors) decides; every pass is
//!   kept (`raised-NNN.csv`, `raised-NNN-K.csv`). Where the stroke also crossed a second line,
//!   the raised passes are compared with the candidate's own dip ([`crackbot_tactile::stroke::own_dip`]), not the
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

//! * **Layers.** The code is in layers that import only downward: the report's types
//!   (`report.rs`, `progress.rs`, `doubts.rs`, `geometry.rs`), the rig (`rig/`: arm, sensor,
//!   live streams, log, recordings, the passes it can command), the steps (`steps/`: one file
//!   or folder per step, each with its section of the configuration), the configuration that
//!   composes the sections (`config.rs`, [`InspectConfig`], checked once into a
//!   [`CheckedConfig`]), the mission that calls the steps in order (`mission.rs`), and this
//!   module, which starts and stops the rig around it.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crackbot_tactile::model::TactileModel;

mod config;
mod config_doc;
mod doubts;
mod geometry;
mod mission;
pub(crate) mod off;
mod progress;
mod report;
pub(crate) mod rig;
pub(crate) mod steps;

pub use config::{CheckedConfig, InspectConfig};
#[cfg(feature = "foxglove")]
pub use crackbot_mcap::DEFAULT_LIVE_ADDR;
pub use doubts::{CrackDoubt, PassDoubt, Width, NOT_JUDGED};
pub use progress::{ArmPose, Feeling, LiveSample, Progress, StreamHealth, StrokeSample};
pub use report::{
    Dip, Evidence, FrameInfo, InspectMode, InspectReport, LinkCounters, PassRecord,
    RejectedCandidate, ReportedCrack, StageTimes,
};
pub use rig::backend::{Connection, HardwareRig, RigBackend};
pub use rig::log::LOG_FILE;
pub use rig::settings::{Hardware, OutputConfig, RigConfig, DEFAULT_BIND};
#[cfg(feature = "sim")]
pub use rig::simulated::SimulatedRig;
pub use rig::site::{ArmLimits, Site};
pub use rig::start::rig_of;
pub use steps::perceive::{CandidateSource, PerceiveConfig};
pub use steps::pieces::{
    turn_deg, PiecesConfig, PIECE_ANGLE_DEG, PIECE_GAP_MM, PIECE_TRACE_GAP_MM,
};
pub use steps::plan::{PlanConfig, TOUCH_MARGIN_MM, TOUCH_MIN_STROKE_MM};
pub use steps::print_check::{
    print_check_height, surface_rise_mm, PrintCheckConfig, MAX_SURFACE_RISE_MM,
    PRINT_CHECK_HEIGHT_MM, PRINT_CHECK_OVERRUN_MM, PRINT_CHECK_PASSES_IN_DOUBT,
    PRINT_CHECK_SPEED_MM_S, PRINT_RATIO_DOUBT, PRINT_RATIO_SETTLED, RAISED_PASS_CLEAR_MM,
    RAISED_PASS_GUARD_COUNTS, SURFACE_RISE_TOLERANCE_MM,
};
pub use steps::rules::{
    doubted_dip_confidence, shallowest_crack_ratio, JudgeConfig, DOUBTED_DIP_CONFIDENCE,
    IMPLAUSIBLE_RATIO_SHARE, WEAK_NO_CRACK_CONFIDENCE,
};
pub use steps::touch::{
    TouchConfig, MIN_DIP_COUNTS, RESTROKE_ALONG_MM, RESTROKE_KEEP_MM, UNEVEN_ENDS_SHARE,
};
pub use steps::trace::{CrackTrace, TRACE_REACH_MM};

use crate::error::io_err;
use crate::MissionError;
use rig::context::Rig;
use rig::log::MissionLog;

/// Runs a mission (see the [module docs](self)) on the rig `config` names ([`rig_of`]): its
/// hardware, or the simulated rig of its scene. `stop` ends it early (the arm is stopped
/// first); `progress` sees each stage. The report is also saved as `report.json` in the
/// mission's folder.
pub fn run_inspection(
    config: &CheckedConfig,
    stop: &AtomicBool,
    progress: impl FnMut(&Progress),
) -> Result<InspectReport, MissionError> {
    let mut rig = rig_of(&config.rig, config.mode)?;
    run_inspection_on(config, rig.as_mut(), stop, progress)
}

/// [`run_inspection`] on a rig of the caller's.
pub fn run_inspection_on(
    config: &CheckedConfig,
    backend: &mut dyn RigBackend,
    stop: &AtomicBool,
    mut progress: impl FnMut(&Progress),
) -> Result<InspectReport, MissionError> {
    let started = Instant::now();
    progress(&Progress::Starting);
    let recognition = TactileModel::load(&config.touch.recognition_model)?;
    let width = TactileModel::load(&config.touch.width_model)?;
    let out_dir = config.output.out_dir.as_path();
    std::fs::create_dir_all(out_dir).map_err(|e| io_err(out_dir, e))?;
    let (mut arm, mut sensor) = match rig::start::start(&config.rig, config.mode, out_dir, backend)
    {
        Ok(parts) => parts,
        Err(e) => {
            backend.shutdown();
            return Err(e);
        }
    };
    let setup_s = started.elapsed().as_secs_f64();
    let mut log = match MissionLog::open(&config.output, arm.t0) {
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
        let mut rig = Rig::new(
            (&config.rig, out_dir),
            &mut arm,
            &mut sensor,
            backend,
            stop,
            &mut logged,
        );
        mission::mission(config, &mut rig, (&recognition, &width), (started, setup_s))
    };
    if result.is_err() {
        arm.stop();
    }
    let counters = arm.counters();
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
    save_report(&out_dir.join("report.json"), &report)?;
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
