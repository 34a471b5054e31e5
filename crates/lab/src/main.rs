//! `crackbot-lab`: what a researcher runs, beside the operator's `crackbot`.
//!
//! * `crackbot-lab tactile convert|eval|paper|tradeoff` — recordings, evaluation protocols, the
//!   paper's tables and the forest's accuracy against run time.
//! * `crackbot-lab eval-detector` — COCO metrics of a detector on any COCO file.
//! * `crackbot-lab detector-tradeoff` — mAP@0.5 against input size against ms per frame.
//! * `crackbot-lab sim dataset|calibrate|work-precision|compare|render|detector-set|scene` — the
//!   simulator.
//! * `crackbot-lab controller-check` — the link's conformance suite against a running controller.
//!
//! The work is done by the libraries (`crackbot-tactile`, `crackbot-vision`, `crackbot-sim`),
//! figures by `crackbot-plots`; this binary parses arguments, draws progress bars and prints.
//! `crackbot <command> …` runs the same commands (it hands them to this binary).

#![expect(
    clippy::needless_pass_by_value,
    reason = "each command's handler takes the arguments clap parsed for it, as its owner"
)]

use anyhow::Result;
use clap::{Parser, Subcommand};

mod args;
mod controller_check;
mod mission;
mod sim;
mod tactile;
mod vision;

/// crackbot-lab: the research tools of crackbot (evaluation, the paper's tables, trade-offs, the
/// simulator's datasets and figures).
#[derive(Debug, Parser)]
#[command(version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Tactile recordings: convert, evaluate, the paper's tables, trade-offs.
    #[command(subcommand)]
    Tactile(tactile::TactileCommand),
    /// COCO metrics (mAP@[.5:.95], mAP@0.5, AR@100) of a detector on any COCO file.
    EvalDetector(vision::EvalDetectorArgs),
    /// Detector accuracy against run time: mAP@0.5 vs input size vs ms per frame (table + PNG).
    DetectorTradeoff(vision::DetectorTradeoffArgs),
    /// The simulator: paper datasets, calibration against real recordings, work-precision,
    /// comparison figures, rendered camera frames, scenes.
    #[command(subcommand)]
    Sim(sim::SimCommand),
    /// The visual-tactile paper's online experiments in simulation: detection trials,
    /// exploration time.
    #[command(subcommand)]
    Mission(mission::MissionCommand),
    /// The link's conformance suite against a running manipulator controller (any maker's):
    /// moves, slides, refusals by field, deadlines, stops, the watchdog, the state stream.
    ControllerCheck(controller_check::ControllerCheckArgs),
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .init();
    match Cli::parse().command {
        Command::Tactile(cmd) => tactile::run(cmd),
        Command::EvalDetector(args) => vision::eval_detector(args),
        Command::DetectorTradeoff(args) => vision::detector_tradeoff(args),
        Command::Sim(cmd) => sim::run(cmd),
        Command::Mission(cmd) => mission::run(cmd),
        Command::ControllerCheck(args) => controller_check::run_check(args),
    }
}
