//! `crackbot-sensor-emulator`: the sensor firmware running on the host, writing 400 Hz frames to
//! a serial device or to a new pseudo-terminal.
//!
//! ```text
//! crackbot-sensor-emulator --pty --duration 10          # prints "PTY /dev/pts/N", then streams
//! crackbot-sensor-emulator --port /dev/ttyUSB1 --baud 115200 --flip-rate 0.01
//! crackbot-sensor-emulator --pty --replay recording.csv  # replays a recording's channels
//! crackbot-sensor-emulator --pty --source sim --crack-width-mm 2   # the physics simulator
//! crackbot-sensor-emulator --pty --source sim --scene crates/sim/scenes/default.toml
//! ```
//!
//! The ADC values come from one of three sources (`--source`):
//!
//! * `synthetic` (the default): a smooth, cheap stand-in of a finger sliding over a crack of
//!   `--crack-width-mm`;
//! * `recording`: the D1, D2, D3, P columns of the CSV recording given with `--replay`, one row
//!   per tick, looping (implied by `--replay`);
//! * `sim`: the physics simulator `crackbot-sim` — the calibrated finger sliding with the paper's
//!   16 mm strokes at 3.89 mm/s across one crack of `--crack-width-mm` (0: a flat plate), each
//!   stroke starting 7 mm before it; or, with `--scene FILE`, across the first crack of that
//!   scene. The simulator advances one 1/400 s sample per tick. If it fails, the ADC holds the
//!   last values, and the emulator exits with an error after the run.

use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::{Parser, ValueEnum};
use crackbot_emulator::{
    run, trace, Corruption, EmulatorConfig, Pty, RecordingSource, SimSource, SyntheticSlide,
    PAPER_SPEED_MM_S, PAPER_STROKE_MM,
};
use crackbot_protocol::SAMPLE_RATE_HZ;
use crackbot_sim::Scene;
use serialport::SerialPort;

/// Where the emulated ADC reads its values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Source {
    /// A smooth stand-in of a finger sliding over a crack of --crack-width-mm.
    Synthetic,
    /// The channels of the recording given with --replay.
    Recording,
    /// The physics simulator: the calibrated finger sliding across a crack of --crack-width-mm,
    /// or across the first crack of --scene.
    Sim,
}

impl Source {
    /// The name on the command line.
    fn name(self) -> &'static str {
        match self {
            Source::Synthetic => "synthetic",
            Source::Recording => "recording",
            Source::Sim => "sim",
        }
    }
}

/// Runs the crackbot sensor firmware on this host and streams its frames over a serial line.
#[derive(Debug, Parser)]
#[command(version, about)]
struct Args {
    /// Create a pseudo-terminal pair and write to it; its device path is printed as the first line
    /// of standard output ("PTY /dev/pts/N"). Open that path with `crackbot record` or the
    /// acquisition library.
    #[arg(long, conflicts_with = "port")]
    pty: bool,
    /// Write to this existing serial device instead (e.g. a USB-serial adapter or a socat PTY).
    #[arg(long, required_unless_present_any = ["pty", "write_trace"])]
    port: Option<String>,
    /// Instead of streaming: write the ADC counts the source gives to this CSV file, one 1/400 s
    /// sample a line, and exit: a trace for the board emulator (`firmware/emulate.sh --trace`).
    /// Length: --frames or --duration; by default, with the sim source, one slide stroke.
    #[arg(long, value_name = "FILE.csv", conflicts_with_all = ["pty", "port"])]
    write_trace: Option<PathBuf>,
    /// UART baud rate (8N1). Frames need 92000 baud at 400 Hz; lower rates make the firmware drop
    /// frames and set the overrun flag, exactly as on the board.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = f64::from(SAMPLE_RATE_HZ))]
    rate: f64,
    /// Stop after this many seconds (default: run until interrupted).
    #[arg(long, conflicts_with = "frames")]
    duration: Option<f64>,
    /// Stop after this many ticks of the sample clock.
    #[arg(long)]
    frames: Option<u64>,
    /// Where the ADC values come from [default: synthetic, or recording with --replay, or sim
    /// with --scene].
    #[arg(long, value_enum)]
    source: Option<Source>,
    /// Replay the D1, D2, D3, P columns of this CSV recording (the `recording` source).
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Crack width of the synthetic slide or of the simulated plate, mm (0 = flat).
    #[arg(long, alias = "crack-width", default_value_t = 5.0)]
    crack_width_mm: f64,
    /// With the `sim` source: slide across the first crack of this scene TOML file (`builtin`:
    /// the built-in default scene) instead of a plate with one crack of --crack-width-mm.
    #[arg(long, conflicts_with_all = ["replay", "crack_width_mm"])]
    scene: Option<PathBuf>,
    /// Probability that a byte on the line is flipped.
    #[arg(long, default_value_t = 0.0)]
    flip_rate: f64,
    /// Probability that a byte on the line is dropped.
    #[arg(long, default_value_t = 0.0)]
    drop_rate: f64,
    /// Probability, per frame, of a garbage burst (1–64 random bytes) before the frame.
    #[arg(long, default_value_t = 0.0)]
    garbage_rate: f64,
    /// Seed of the signal noise and of the corruption.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the sequence numbers of the corrupted frames and the fault counts to this JSON file.
    #[arg(long)]
    corruption_log: Option<PathBuf>,
    /// Wait for a line on standard input before streaming (lets a reader open the PTY first).
    #[arg(long)]
    wait_for_start: bool,
    /// Keep the device open this long after the last frame so a reader can drain it, ms.
    #[arg(long, default_value_t = 500)]
    linger_ms: u64,
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .init();
    let args = Args::parse();
    let corruption = Corruption {
        flip_rate: args.flip_rate,
        drop_rate: args.drop_rate,
        garbage_rate: args.garbage_rate,
    };
    corruption.validate()?;
    if !(args.rate.is_finite() && args.rate > 0.0) {
        bail!("--rate must be a positive number of Hz, got {}", args.rate);
    }
    let ticks = ticks_of(&args)?;
    let source = source_kind(&args)?;
    // Set up the simulator before the port opens, so a bad scene fails before anything streams.
    let mut sim = match source {
        Source::Sim => Some(checked_sim_source(&args)?),
        _ => None,
    };
    if let Some(path) = &args.write_trace {
        return write_trace_file(&args, source, sim, ticks, path);
    }
    let config = EmulatorConfig {
        rate_hz: args.rate,
        baud: args.baud,
        ticks,
        corruption,
        seed: args.seed,
    };

    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))
            .context("installing the SIGINT/SIGTERM handler")?;
    }

    // Keep the slave side of a PTY open for the whole run so its raw settings stay in force.
    let (mut port, _slave) = open_port(&args)?;

    if args.wait_for_start {
        let mut line = String::new();
        std::io::stdin()
            .lock()
            .read_line(&mut line)
            .context("waiting for the start line on stdin")?;
    }

    let result = match source {
        Source::Recording => {
            run(&config, recording_source(&args)?, &mut port, &stop).map(|r| (r, None))
        }
        Source::Synthetic => {
            run(&config, synthetic_source(&args), &mut port, &stop).map(|r| (r, None))
        }
        Source::Sim => {
            let mut source = sim.take().context("the sim source was not set up")?;
            let report = run(&config, &mut source, &mut port, &stop)?;
            let failure = source.error().map(|e| {
                format!(
                    "the simulation failed after {} samples ({e}); the ADC held the last values from then on",
                    source.samples()
                )
            });
            Ok((report, failure))
        }
    };
    let (report, sim_failure) = result?;
    std::thread::sleep(Duration::from_millis(args.linger_ms));
    if let Some(path) = &args.corruption_log {
        std::fs::write(path, serde_json::to_string_pretty(&report.corruption)?)
            .with_context(|| format!("writing the corruption log {}", path.display()))?;
    }
    println!("{}", serde_json::to_string(&report)?);
    tracing::info!(
        ticks = report.ticks,
        queued = report.frames_queued,
        dropped = report.frames_dropped,
        corrupted = report.corruption.damaged_seqs.len(),
        "emulator done in {:.2} s",
        report.seconds
    );
    if let Some(failure) = sim_failure {
        bail!(failure);
    }
    Ok(())
}

/// The run's length in ticks, from `--duration` or `--frames` (None: until stopped).
fn ticks_of(args: &Args) -> Result<Option<u64>> {
    Ok(match (args.duration, args.frames) {
        (Some(d), _) if !(d.is_finite() && d >= 0.0) => {
            bail!("--duration must be a non-negative number of seconds, got {d}")
        }
        (Some(d), _) => Some((d * args.rate).round() as u64),
        (None, n) => n,
    })
}

/// The simulator for `--source sim`, warning when `--rate` makes it run off real time.
fn checked_sim_source(args: &Args) -> Result<SimSource> {
    let native = f64::from(SAMPLE_RATE_HZ);
    if args.rate != native {
        tracing::warn!(
            "the simulator advances 1/{native} s per tick: at {} Hz the simulated slide runs {:.2}× real time",
            args.rate,
            args.rate / native
        );
    }
    sim_source(args)
}

/// A port and, for `--pty`, the slave side to keep open.
type OpenPort = (Box<dyn SerialPort>, Option<Box<dyn SerialPort>>);

/// `--pty` (a new pseudo-terminal, its path printed) or `--port PATH`.
fn open_port(args: &Args) -> Result<OpenPort> {
    if args.pty {
        let pty = Pty::open()?;
        println!("PTY {}", pty.path());
        std::io::stdout().flush()?;
        let (master, slave) = pty.into_parts();
        return Ok((Box::new(master), Some(Box::new(slave))));
    }
    let path = args.port.clone().unwrap_or_default();
    if !std::path::Path::new(&path).exists() {
        bail!("serial device {path} does not exist");
    }
    let port = serialport::new(&path, args.baud)
        .timeout(Duration::from_secs(1))
        .open()
        .with_context(|| format!("opening serial device {path} at {} baud", args.baud))?;
    Ok((port, None))
}

/// The source the arguments ask for, with the implied defaults, rejecting settings that belong
/// to another source.
fn source_kind(args: &Args) -> Result<Source> {
    let source = match (args.source, &args.replay, &args.scene) {
        (Some(s), _, _) => s,
        (None, Some(_), _) => Source::Recording,
        (None, None, Some(_)) => Source::Sim,
        (None, None, None) => Source::Synthetic,
    };
    if args.replay.is_some() && source != Source::Recording {
        bail!("--replay is for --source recording, not {}", source.name());
    }
    if args.scene.is_some() && source != Source::Sim {
        bail!("--scene is for --source sim, not {}", source.name());
    }
    if source == Source::Recording && args.replay.is_none() {
        bail!("--source recording needs the recording to replay: --replay FILE.csv");
    }
    if !(args.crack_width_mm.is_finite() && args.crack_width_mm >= 0.0) {
        bail!(
            "--crack-width-mm must be a non-negative number of mm, got {}",
            args.crack_width_mm
        );
    }
    Ok(source)
}

/// `--write-trace`: the source's counts, `ticks` samples (one stroke of the sim slide by
/// default), to `path`.
fn write_trace_file(
    args: &Args,
    source: Source,
    sim: Option<SimSource>,
    ticks: Option<u64>,
    path: &std::path::Path,
) -> Result<()> {
    let samples = match (ticks, source) {
        (Some(n), _) => n,
        (None, Source::Sim) => match &args.scene {
            Some(scene) => trace::stroke_samples(&load_scene(scene)?),
            None => (PAPER_STROKE_MM / PAPER_SPEED_MM_S * f64::from(SAMPLE_RATE_HZ)).ceil() as u64,
        },
        (None, _) => bail!("--write-trace needs --frames or --duration with this source"),
    };
    let file = std::fs::File::create(path)
        .with_context(|| format!("creating the trace {}", path.display()))?;
    let out = std::io::BufWriter::new(file);
    let written = match source {
        Source::Sim => {
            let mut sim = sim.context("the sim source was not set up")?;
            let written = trace::write_trace(&mut sim, samples, out);
            if let Some(e) = sim.error() {
                bail!("the simulation failed after {} samples: {e}", sim.samples());
            }
            written
        }
        Source::Recording => trace::write_trace(recording_source(args)?, samples, out),
        Source::Synthetic => trace::write_trace(synthetic_source(args), samples, out),
    };
    written.with_context(|| format!("writing the trace {}", path.display()))?;
    eprintln!("wrote {samples} samples to {}", path.display());
    Ok(())
}

/// `--source recording`: the channels of `--replay`.
fn recording_source(args: &Args) -> Result<RecordingSource> {
    let path = args
        .replay
        .as_deref()
        .context("--source recording needs --replay")?;
    let rec = crackbot_recording::read_csv(path)?;
    RecordingSource::new(rec).with_context(|| format!("recording {} has no rows", path.display()))
}

/// `--source synthetic`: the smooth stand-in over a crack of `--crack-width-mm`.
fn synthetic_source(args: &Args) -> SyntheticSlide {
    let mut source = SyntheticSlide::new(args.seed);
    source.crack_width_mm = args.crack_width_mm;
    source
}

/// A scene file, or the built-in default scene for `builtin`.
fn load_scene(path: &std::path::Path) -> Result<Scene> {
    if path.as_os_str() == "builtin" && !path.exists() {
        Ok(Scene::builtin_default())
    } else {
        Ok(Scene::load(path)?)
    }
}

/// Sets up the simulator for `--source sim`.
fn sim_source(args: &Args) -> Result<SimSource> {
    match &args.scene {
        Some(path) => {
            let scene = load_scene(path)?;
            SimSource::across_first_crack(&scene, args.seed).with_context(|| {
                format!(
                    "setting up the simulator across the first crack of {}",
                    path.display()
                )
            })
        }
        None => SimSource::over_crack(args.crack_width_mm, args.seed).with_context(|| {
            format!(
                "setting up the simulator over a {} mm crack",
                args.crack_width_mm
            )
        }),
    }
}
