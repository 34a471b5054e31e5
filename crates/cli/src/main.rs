//! `crackbot`: what an operator runs (the headless tool of the robot's computer). Research tools
//! (the paper's tables, trade-offs, detector metrics, the simulator's datasets and figures) are
//! in `crackbot-lab`; `crackbot tactile|sim|eval-detector|detector-tradeoff …` hands those to it
//! with the same arguments, so every command works from here too.
//!
//! * `crackbot demo` — the acquisition demo: the sensor firmware runs on this host, streams
//!   400 Hz frames into a pseudo-terminal, the acquisition reads them back over the real serial
//!   path, records them to CSV and prints a summary.
//! * `crackbot record --port PATH` — records a real (or emulated) sensor to CSV until Ctrl-C,
//!   a time limit, or the port going away; nothing received is lost on any of these.
//! * `crackbot replay FILE` — plays a recording back at its original or an accelerated rate.
//! * `crackbot calibration check FILE` — validates a calibration file.
//! * `crackbot detect IMAGE...` — candidate cracks in camera images (ONNX detector or the
//!   classical baseline), with surface millimetres given a homography calibration.
//! * `crackbot homography fit|check` — the camera's pixel ↔ millimetre calibration from
//!   measured point pairs.
//! * `crackbot calibrate target|camera|surface|views|check` — the camera from a printed target:
//!   lens distortion included, the plate's pose, checks drawn on the frames.
//!
//! The work is done by the libraries (`crackbot-mission`, `crackbot-acquisition`,
//! `crackbot-vision`); this binary parses arguments, draws progress bars and prints reports.

#![expect(
    clippy::needless_pass_by_value,
    reason = "each command's handler takes the arguments clap parsed for it, as its owner"
)]

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use crackbot_acquisition::calibration::Calibration;
use crackbot_acquisition::session::summarise_replay;
use crackbot_acquisition::{
    PortConfig, RecordEnd, RecordMeta, RecordSession, Replay, ReplaySpeed, StreamReport,
};
#[cfg(feature = "sim")]
use crackbot_mission::{run_demo, DemoConfig, DemoSurface};
#[cfg(feature = "sim")]
use crackbot_protocol::SAMPLE_RATE_HZ;
use indicatif::{ProgressBar, ProgressStyle};

mod calibrate;
mod commission;
mod finger;
mod lab;
mod log;
mod run;
mod vision;

/// crackbot: find surface cracks with a camera and a fibre-optic tactile finger.
#[derive(Debug, Parser)]
#[command(version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Inspection mission: look, touch, report (fused by default, on the built-in default
    /// scene); the headless robot `crackbot-robot` with the same flags.
    Run(Box<run::RunArgs>),
    /// Acquisition demo on the built-in default scene: simulated finger → emulated sensor →
    /// pseudo-terminal → acquisition → CSV → summary.
    #[cfg(feature = "sim")]
    Demo(DemoArgs),
    /// Record a sensor's serial stream to CSV.
    Record(RecordArgs),
    /// Play a recording (CSV, or an MCAP log) back as a stream and summarise it.
    Replay(ReplayArgs),
    /// Calibration files.
    #[command(subcommand)]
    Calibration(CalibrationCommand),
    /// Find cracks in camera images (boxes, scores, surface millimetres with a calibration).
    Detect(vision::DetectArgs),
    /// Pixel ↔ surface-millimetre calibration of the camera (homography).
    #[command(subcommand)]
    Homography(vision::HomographyCommand),
    /// The camera from a printed target: the target to print, the lens (intrinsics and
    /// distortion), the plate's pose.
    #[command(subcommand)]
    Calibrate(calibrate::CalibrateCommand),
    /// A mission's log in other forms: `crackbot log to-ros2 out/mission` writes the ROS 2 bag
    /// that `ros2 bag play` plays.
    #[command(subcommand)]
    Log(log::LogCommand),
    /// Commission a new finger: print the reference plates, let the arm slide over them, train
    /// and install the finger's own models as a profile (`crackbot run --finger NAME`).
    #[command(subcommand)]
    Commission(commission::CommissionCommand),
    /// [research, runs crackbot-lab] Tactile recordings: convert, evaluate, the paper's tables.
    #[command(disable_help_flag = true)]
    Tactile(lab::Forwarded),
    /// [research, runs crackbot-lab] COCO metrics of a detector on any COCO file.
    #[command(disable_help_flag = true)]
    EvalDetector(lab::Forwarded),
    /// [research, runs crackbot-lab] Detector accuracy against run time.
    #[command(disable_help_flag = true)]
    DetectorTradeoff(lab::Forwarded),
    /// [research, runs crackbot-lab] The simulator: datasets, calibration, figures, scenes.
    #[command(disable_help_flag = true)]
    Sim(lab::Forwarded),
    /// [research, runs crackbot-lab] The paper's online experiments in simulation.
    #[command(disable_help_flag = true)]
    Mission(lab::Forwarded),
}

#[cfg(feature = "sim")]
#[derive(Debug, Args)]
struct DemoArgs {
    /// Seconds of sensor data to stream.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Where to write the recording.
    #[arg(long, default_value = "out/demo-recording.csv")]
    out: PathBuf,
    /// Probability of a flipped byte on the emulated line (shows the decoder's resync).
    #[arg(long, default_value_t = 0.0)]
    flip_rate: f64,
    /// Scene the simulated finger slides on, across its first crack (default: the built-in
    /// default scene).
    #[arg(long, conflicts_with = "crack_width")]
    scene: Option<PathBuf>,
    /// Instead of a scene: a plate with one crack of this width, mm.
    #[arg(long)]
    crack_width: Option<f64>,
    /// Calibration file to report physical units with (default: the example calibration).
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct RecordArgs {
    /// Serial device of the sensor, e.g. /dev/ttyACM0.
    #[arg(long)]
    port: String,
    /// Baud rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Output CSV file.
    #[arg(long, short)]
    out: PathBuf,
    /// Stop after this many seconds (default: until Ctrl-C or the port goes away).
    #[arg(long)]
    seconds: Option<f64>,
    /// Also write the samples as an MCAP log (Foxglove, PlotJuggler; the `/tactile` channel,
    /// each sample stamped with the host's clock), beside the CSV.
    #[arg(long, value_name = "FILE")]
    mcap: Option<PathBuf>,
    /// Label written in column 8 (surface class, or crack width in mm).
    #[arg(long, default_value_t = 0.0)]
    label: f64,
    /// Repetition number written in column 9.
    #[arg(long, default_value_t = 1)]
    repetition: u32,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct ReplayArgs {
    /// CSV recording, or an MCAP log (`mission.mcap`, `crackbot record --mcap`): its
    /// `/tactile` samples.
    file: PathBuf,
    /// Speed-up factor (1 = original rate).
    #[arg(long, default_value_t = 1.0, conflicts_with = "unpaced")]
    speed: f64,
    /// Replay as fast as possible.
    #[arg(long)]
    unpaced: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Subcommand)]
enum CalibrationCommand {
    /// Load and validate a calibration file; print its condition number.
    Check {
        /// Calibration TOML file.
        file: PathBuf,
    },
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn".into()),
        )
        .init();
    let cli = Cli::parse();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    match cli.command {
        Command::Run(args) => run::run(*args),
        #[cfg(feature = "sim")]
        Command::Demo(args) => runtime.block_on(demo(args)),
        Command::Record(args) => runtime.block_on(record(args)),
        Command::Replay(args) => runtime.block_on(replay(args)),
        Command::Detect(args) => vision::detect(args),
        Command::Homography(cmd) => vision::homography(cmd),
        Command::Calibrate(cmd) => calibrate::calibrate(cmd),
        Command::Commission(cmd) => commission::commission_cmd(cmd),
        Command::Log(cmd) => log::log_cmd(cmd),
        Command::Tactile(args) => lab::run("tactile", args),
        Command::EvalDetector(args) => lab::run("eval-detector", args),
        Command::DetectorTradeoff(args) => lab::run("detector-tradeoff", args),
        Command::Sim(args) => lab::run("sim", args),
        Command::Mission(args) => lab::run("mission", args),
        Command::Calibration(CalibrationCommand::Check { file }) => {
            let cal = Calibration::load(&file)?;
            println!(
                "{}: sensor {}, condition number {:.3e}: OK",
                file.display(),
                cal.sensor_id,
                cal.condition_number()
            );
            Ok(())
        }
    }
}

/// Prints a stream summary: human text, or one JSON object with `--json`.
fn print_summary(title: &str, report: &StreamReport, json: bool) -> Result<()> {
    if json {
        println!("{}", serde_json::to_string(report)?);
        return Ok(());
    }
    print_summary_text(title, report);
    Ok(())
}

fn print_summary_text(title: &str, r: &StreamReport) {
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    println!("{title}");
    println!("  samples            {}", r.samples);
    println!("  rate, host clock   {} Hz", f(r.host_rate_hz));
    println!("  rate, device clock {} Hz", f(r.device_rate_hz));
    println!(
        "  device time        {}",
        if r.device_time_monotonic {
            "monotonic"
        } else {
            "NOT monotonic"
        }
    );
    println!("  channel    min    max     mean");
    for (c, name) in r.channels.iter().enumerate() {
        println!(
            "  {name:<7} {:>6} {:>6} {:>8.1}",
            r.min[c], r.max[c], r.mean[c]
        );
    }
    if let Some(cal) = &r.calibrated_mean {
        println!("  calibrated mean ({}):", cal.sensor);
        for i in 0..4 {
            println!(
                "    {:<40} {:>10.4} {}",
                cal.outputs[i], cal.mean[i], cal.units[i]
            );
        }
    }
    let l = &r.link;
    println!(
        "  link: {} bytes, {} frames, {} CRC errors, {} resyncs, {} gaps ({} frames missing), {} overrun flags, {} device restarts, delivery {:.4}",
        l.decoder.bytes, l.decoder.frames, l.decoder.crc_errors, l.resyncs, l.gaps, l.missing_frames, l.overrun_flags,
        l.restarts, r.delivery_ratio
    );
}

fn progress(total: Option<u64>) -> ProgressBar {
    let bar = match total {
        Some(n) => ProgressBar::new(n),
        None => ProgressBar::new_spinner(),
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} samples {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// Completes on Ctrl-C (never, if the handler cannot be installed).
async fn ctrl_c() {
    if tokio::signal::ctrl_c().await.is_err() {
        std::future::pending::<()>().await;
    }
}

async fn record(args: RecordArgs) -> Result<()> {
    let mut port = PortConfig::new(&args.port);
    port.baud = args.baud;
    let session = RecordSession {
        port,
        out: args.out.clone(),
        meta: RecordMeta {
            label: args.label,
            repetition: args.repetition,
            ..RecordMeta::default()
        },
        limit: args.seconds.map(Duration::from_secs_f64),
    };
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        progress(None)
    };
    let log = match &args.mcap {
        Some(path) => Some(crackbot_mcap::LogWriter::create(
            path,
            crackbot_mcap::unix_ns(std::time::SystemTime::now()),
        )?),
        None => None,
    };
    let mut log_error = None;
    let report = session
        .run(ctrl_c(), |s| {
            bar.inc(1);
            if let Some(log) = &log {
                if let Err(e) = log_sample(log, s) {
                    log_error.get_or_insert(e);
                }
            }
        })
        .await;
    bar.finish_and_clear();
    if let Some(log) = log {
        let path = log.finish()?;
        if let Some(e) = log_error {
            return Err(e.into());
        }
        eprintln!("logged the samples to {}", path.display());
    }
    let report = report?;
    if matches!(report.ended_by, RecordEnd::Stopped) {
        eprintln!("interrupted: the recording is flushed");
    }
    eprintln!("recorded {} rows to {}", report.rows, report.out.display());
    print_summary(
        &format!("recording of {}", args.port),
        &report.stream,
        args.json,
    )?;
    if let RecordEnd::Disconnected(e) = report.ended_by {
        return Err(e).with_context(|| {
            format!(
                "recording stopped; {} rows saved to {}",
                report.rows,
                report.out.display()
            )
        });
    }
    Ok(())
}

#[cfg(feature = "sim")]
async fn demo(args: DemoArgs) -> Result<()> {
    let calibration = match &args.calibration {
        Some(path) => Calibration::load(path)?,
        None => Calibration::example()?,
    };
    let surface = match (&args.crack_width, &args.scene) {
        (Some(width), _) => DemoSurface::Crack { width_mm: *width },
        (None, Some(path)) => DemoSurface::SceneFile(path.clone()),
        (None, None) => DemoSurface::BuiltinScene,
    };
    let config = DemoConfig {
        seconds: args.seconds,
        out: args.out.clone(),
        flip_rate: args.flip_rate,
        surface,
        calibration,
    };
    let bar = if args.json || !(args.seconds.is_finite() && args.seconds > 0.0) {
        ProgressBar::hidden()
    } else {
        progress(Some(
            (args.seconds * f64::from(SAMPLE_RATE_HZ)).round() as u64
        ))
    };
    let out = args.out.display().to_string();
    let report = run_demo(
        &config,
        ctrl_c(),
        |port| {
            if !args.json {
                bar.println(format!(
                    "emulated sensor on {port} ({SAMPLE_RATE_HZ} Hz, 115200 baud) → acquisition → {out}"
                ));
            }
        },
        |_| bar.inc(1),
    )
    .await;
    bar.finish_and_clear();
    let report = report?;
    if args.json {
        println!("{}", serde_json::to_string(&report)?);
        return Ok(());
    }
    print_summary_text(
        &format!(
            "acquisition demo: {} s of emulated sensor over {}",
            args.seconds, report.port
        ),
        &report.stream,
    );
    println!(
        "  recording          {} ({} rows)",
        report.recording, report.rows_written
    );
    Ok(())
}

/// One recorded sample on the log's `/tactile` channel (its time: since the port opened).
fn log_sample(
    log: &crackbot_mcap::LogWriter,
    s: &crackbot_acquisition::Sample,
) -> Result<(), crackbot_mcap::LogError> {
    let m = crackbot_mcap::SampleMessage::new(s.host_time.as_secs_f64(), s.raw, None, None);
    log.sample(crackbot_mcap::JsonTopic::Tactile, &m)
}

/// A CSV recording, or the `/tactile` channel of an MCAP log (a mission's `mission.mcap`, or
/// `crackbot record --mcap`) as one.
fn recording_of(path: &std::path::Path) -> Result<crackbot_recording::Recording> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
    {
        let log = crackbot_mcap::read_log(path)?;
        let rows = crackbot_mcap::tactile_rows(&log)
            .with_context(|| format!("{}: the /tactile channel", path.display()))?;
        if rows.is_empty() {
            bail!("{}: no /tactile samples in this log", path.display());
        }
        return Ok(crackbot_recording::Recording {
            rows: rows
                .iter()
                .map(|r| crackbot_recording::Row {
                    x_mm: r.along_mm.unwrap_or(0.0),
                    d1: f64::from(r.raw[0]),
                    d2: f64::from(r.raw[1]),
                    d3: f64::from(r.raw[2]),
                    p: f64::from(r.raw[3]),
                    direction: 0,
                    slide: r.slide.unwrap_or(0),
                    label: 0.0,
                    repetition: 1,
                })
                .collect(),
            extra: None,
        });
    }
    Ok(crackbot_recording::read_csv(path)?)
}

async fn replay(args: ReplayArgs) -> Result<()> {
    let recording = recording_of(&args.file)?;
    let speed = if args.unpaced {
        ReplaySpeed::Unpaced
    } else if args.speed.is_finite() && args.speed > 0.0 {
        ReplaySpeed::Factor(args.speed)
    } else {
        bail!("--speed must be a positive factor, got {}", args.speed)
    };
    let replay = Replay::new(&recording, speed);
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        progress(Some(replay.remaining() as u64))
    };
    let report = summarise_replay(replay, None, |_| bar.inc(1)).await;
    bar.finish_and_clear();
    print_summary(
        &format!("replay of {}", args.file.display()),
        &report,
        args.json,
    )
}
