//! `crackbot`: the command line of the crackbot crack-inspection system.
//!
//! * `crackbot demo` — the acquisition demo: the sensor firmware runs on this host, streams
//!   400 Hz frames into a pseudo-terminal, the acquisition reads them back over the real serial
//!   path, records them to CSV and prints a summary.
//! * `crackbot record --port PATH` — records a real (or emulated) sensor to CSV until Ctrl-C,
//!   a time limit, or the port going away; nothing received is lost on any of these.
//! * `crackbot replay FILE` — plays a recording back at its original or an accelerated rate.
//! * `crackbot calibration check FILE` — validates a calibration file.
//! * `crackbot tactile convert INPUT... --out DIR|FILE` — converts tactile recordings between the
//!   authors' `.mat` files and `.csv`.
//! * `crackbot detect IMAGE...` — candidate cracks in camera images (ONNX detector or the
//!   classical baseline), with surface millimetres given a homography calibration.
//! * `crackbot eval-detector --coco FILE` — COCO metrics of a detector on any COCO file.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use crackbot_acquisition::calibration::Calibration;
use crackbot_acquisition::{
    AcquisitionError, LinkStats, PortConfig, RecordMeta, Replay, ReplaySpeed, Sample,
    SampleRecorder, SensorStream,
};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use serialport::SerialPort as _;

mod sim;
mod tactile;
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
    /// Acquisition demo on the built-in default scene: simulated finger → emulated sensor →
    /// pseudo-terminal → acquisition → CSV → summary.
    Demo(DemoArgs),
    /// Record a sensor's serial stream to CSV.
    Record(RecordArgs),
    /// Play a CSV recording back as a stream and summarise it.
    Replay(ReplayArgs),
    /// Calibration files.
    #[command(subcommand)]
    Calibration(CalibrationCommand),
    /// Tactile recordings: convert the authors' .mat files and .csv recordings.
    #[command(subcommand)]
    Tactile(tactile::TactileCommand),
    /// Find cracks in camera images (boxes, scores, surface millimetres with a calibration).
    Detect(vision::DetectArgs),
    /// COCO metrics (mAP@[.5:.95], mAP@0.5, AR@100) of a detector on any COCO file.
    EvalDetector(vision::EvalDetectorArgs),
    /// Detector accuracy against run time: mAP@0.5 vs input size vs ms per frame (table + PNG).
    DetectorTradeoff(vision::DetectorTradeoffArgs),
    /// Pixel ↔ surface-millimetre calibration of the camera (homography).
    #[command(subcommand)]
    Homography(vision::HomographyCommand),
    /// The simulator: paper datasets, calibration against real recordings, work-precision.
    #[command(subcommand)]
    Sim(sim::SimCommand),
}

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
    /// CSV recording.
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
        Command::Demo(args) => runtime.block_on(demo(args)),
        Command::Record(args) => runtime.block_on(record(args)),
        Command::Replay(args) => runtime.block_on(replay(args)),
        Command::Tactile(cmd) => tactile::run(cmd),
        Command::Detect(args) => vision::detect(args),
        Command::EvalDetector(args) => vision::eval_detector(args),
        Command::DetectorTradeoff(args) => vision::detector_tradeoff(args),
        Command::Homography(cmd) => vision::homography(cmd),
        Command::Sim(cmd) => sim::run(cmd),
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

/// Statistics of the samples of a run.
#[derive(Debug, Default)]
struct Summary {
    samples: u64,
    first_host: Option<Duration>,
    last_host: Duration,
    first_device: Option<u64>,
    last_device: u64,
    backwards_device_time: u64,
    min: [u16; 4],
    max: [u16; 4],
    sum: [f64; 4],
}

impl Summary {
    fn add(&mut self, s: &Sample) {
        if self.samples == 0 {
            self.min = s.raw;
            self.max = s.raw;
        }
        if self.first_device.is_some() && s.device_time_us < self.last_device {
            self.backwards_device_time += 1;
        }
        self.samples += 1;
        self.first_host.get_or_insert(s.host_time);
        self.first_device.get_or_insert(s.device_time_us);
        self.last_host = s.host_time;
        self.last_device = s.device_time_us;
        for c in 0..4 {
            self.min[c] = self.min[c].min(s.raw[c]);
            self.max[c] = self.max[c].max(s.raw[c]);
            self.sum[c] += f64::from(s.raw[c]);
        }
    }

    fn rate(span_us: f64, samples: u64) -> Option<f64> {
        (samples > 1 && span_us > 0.0).then(|| (samples - 1) as f64 / (span_us * 1e-6))
    }

    fn to_json(&self, link: &LinkStats, calibration: Option<&Calibration>) -> serde_json::Value {
        let host_span = self
            .last_host
            .saturating_sub(self.first_host.unwrap_or_default())
            .as_micros() as f64;
        let device_span = (self.last_device - self.first_device.unwrap_or(0)) as f64;
        let mean = self.sum.map(|s| {
            if self.samples > 0 {
                s / self.samples as f64
            } else {
                f64::NAN
            }
        });
        let physical = calibration.map(|c| {
            let p = c.apply(mean.map(|m| m.round().clamp(0.0, 65535.0) as u16));
            json!({ "sensor": c.sensor_id, "outputs": c.outputs, "units": c.units, "mean": p })
        });
        json!({
            "samples": self.samples,
            "host_rate_hz": Self::rate(host_span, self.samples),
            "device_rate_hz": Self::rate(device_span, self.samples),
            "device_time_monotonic": self.backwards_device_time == 0,
            "channels": ["D1", "D2", "D3", "P"],
            "min": self.min, "max": self.max, "mean": mean,
            "calibrated_mean": physical,
            "link": link,
            "delivery_ratio": link.delivery_ratio(),
        })
    }
}

fn print_summary(title: &str, value: &serde_json::Value, json: bool) {
    if json {
        println!("{value}");
        return;
    }
    let f = |k: &str| {
        value[k]
            .as_f64()
            .map_or("-".to_string(), |v| format!("{v:.2}"))
    };
    println!("{title}");
    println!("  samples            {}", value["samples"]);
    println!("  rate, host clock   {} Hz", f("host_rate_hz"));
    println!("  rate, device clock {} Hz", f("device_rate_hz"));
    println!(
        "  device time        {}",
        if value["device_time_monotonic"] == true {
            "monotonic"
        } else {
            "NOT monotonic"
        }
    );
    println!("  channel    min    max     mean");
    for (c, name) in ["D1", "D2", "D3", "P"].iter().enumerate() {
        println!(
            "  {name:<7} {:>6} {:>6} {:>8.1}",
            value["min"][c].as_u64().unwrap_or(0),
            value["max"][c].as_u64().unwrap_or(0),
            value["mean"][c].as_f64().unwrap_or(f64::NAN)
        );
    }
    if let Some(cal) = value["calibrated_mean"].as_object() {
        println!(
            "  calibrated mean ({}):",
            cal["sensor"].as_str().unwrap_or("?")
        );
        for i in 0..4 {
            println!(
                "    {:<40} {:>10.4} {}",
                cal["outputs"][i].as_str().unwrap_or("?"),
                cal["mean"][i].as_f64().unwrap_or(f64::NAN),
                cal["units"][i].as_str().unwrap_or("")
            );
        }
    }
    let l = &value["link"];
    println!(
        "  link: {} bytes, {} frames, {} CRC errors, {} resyncs, {} gaps ({} frames missing), {} overrun flags, delivery {:.4}",
        l["bytes"], l["frames"], l["crc_errors"], l["resyncs"], l["gaps"], l["missing_frames"], l["overrun_flags"],
        value["delivery_ratio"].as_f64().unwrap_or(f64::NAN)
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

/// Reads `stream` into `recorder` until `deadline_samples`, Ctrl-C or a disconnect. Returns the
/// summary and the disconnect error, if that is how it ended.
async fn pump(
    stream: &mut SensorStream,
    recorder: &mut SampleRecorder,
    meta: &RecordMeta,
    max_seconds: Option<f64>,
    bar: &ProgressBar,
) -> Result<(Summary, Option<AcquisitionError>)> {
    let mut summary = Summary::default();
    let limit = max_seconds.map(Duration::from_secs_f64);
    let started = Instant::now();
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    let mut ended_by = None;
    loop {
        let remaining = limit.map(|l| l.saturating_sub(started.elapsed()));
        if remaining == Some(Duration::ZERO) {
            break;
        }
        let timeout = tokio::time::sleep(remaining.unwrap_or(Duration::from_secs(3600)));
        tokio::select! {
            item = stream.next() => match item {
                Some(Ok(sample)) => {
                    recorder.record(&sample, meta)?;
                    summary.add(&sample);
                    bar.inc(1);
                }
                Some(Err(e)) => { ended_by = Some(e); break; }
                None => break,
            },
            _ = &mut ctrl_c => { bar.println("interrupted: flushing the recording"); break; }
            _ = timeout => {}
        }
    }
    // Whatever the reader thread already received is recorded too.
    stream.stop();
    while let Ok(Some(Ok(sample))) =
        tokio::time::timeout(Duration::from_millis(200), stream.next()).await
    {
        recorder.record(&sample, meta)?;
        summary.add(&sample);
    }
    Ok((summary, ended_by))
}

async fn record(args: RecordArgs) -> Result<()> {
    let mut config = PortConfig::new(&args.port);
    config.baud = args.baud;
    let mut stream = SensorStream::open(&config)?;
    create_parent(&args.out)?;
    let mut recorder = SampleRecorder::create(&args.out)?;
    let meta = RecordMeta {
        label: args.label,
        repetition: args.repetition,
        ..RecordMeta::default()
    };
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        progress(None)
    };
    let outcome = pump(&mut stream, &mut recorder, &meta, args.seconds, &bar).await;
    bar.finish_and_clear();
    let link = stream.stats();
    // Flush before anything else can fail.
    let rows = recorder.finish()?;
    let (summary, ended_by) = outcome?;
    let value = summary.to_json(&link, None);
    eprintln!("recorded {rows} rows to {}", args.out.display());
    print_summary(&format!("recording of {}", args.port), &value, args.json);
    if let Some(e) = ended_by {
        return Err(e).with_context(|| {
            format!(
                "recording stopped; {rows} rows saved to {}",
                args.out.display()
            )
        });
    }
    Ok(())
}

async fn demo(args: DemoArgs) -> Result<()> {
    if !(args.seconds.is_finite() && args.seconds > 0.0) {
        bail!("--seconds must be positive, got {}", args.seconds);
    }
    let calibration = match &args.calibration {
        Some(path) => Calibration::load(path)?,
        None => Calibration::from_toml_str(EXAMPLE_CALIBRATION, "built-in example calibration")?,
    };
    let (master, slave) = serialport::TTYPort::pair().context("creating a pseudo-terminal pair")?;
    let path = slave
        .name()
        .context("the pseudo-terminal has no device path")?;
    let mut stream = SensorStream::open(&PortConfig::new(&path))?;
    let config = crackbot_emulator::EmulatorConfig {
        ticks: Some((args.seconds * 400.0).round() as u64),
        corruption: crackbot_emulator::Corruption {
            flip_rate: args.flip_rate,
            ..Default::default()
        },
        ..Default::default()
    };
    config.corruption.validate()?;
    let stop = Arc::new(AtomicBool::new(false));
    let emulator_stop = stop.clone();
    // The simulator drives the emulated sensor: the finger sliding across the scene's first
    // crack (or a plate with one crack of the given width).
    let source = match (&args.crack_width, &args.scene) {
        (Some(width), _) => crackbot_emulator::SimSource::over_crack(*width, 7)?,
        (None, Some(path)) => {
            crackbot_emulator::SimSource::across_first_crack(&crackbot_sim::Scene::load(path)?, 7)?
        }
        (None, None) => crackbot_emulator::SimSource::across_first_crack(
            &crackbot_sim::Scene::builtin_default(),
            7,
        )?,
    };
    let emulator = std::thread::spawn(move || {
        let mut master = master;
        let report = crackbot_emulator::run(&config, source, &mut master, &emulator_stop);
        // Keep the PTY open until the reader has drained it.
        std::thread::sleep(Duration::from_millis(300));
        drop(slave);
        report
    });
    create_parent(&args.out)?;
    let mut recorder = SampleRecorder::create(&args.out)?;
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        progress(Some((args.seconds * 400.0) as u64))
    };
    if !args.json {
        eprintln!(
            "emulated sensor on {path} (400 Hz, 115200 baud) → acquisition → {}",
            args.out.display()
        );
    }
    let outcome = pump(
        &mut stream,
        &mut recorder,
        &RecordMeta::default(),
        Some(args.seconds + 1.0),
        &bar,
    )
    .await;
    bar.finish_and_clear();
    stop.store(true, Ordering::Relaxed);
    let report = emulator
        .join()
        .map_err(|_| anyhow::anyhow!("the emulator thread panicked"))??;
    let link = stream.stats();
    let rows = recorder.finish()?;
    let (summary, _) = outcome?;
    let mut value = summary.to_json(&link, Some(&calibration));
    value["recording"] = json!(args.out.display().to_string());
    value["rows_written"] = json!(rows);
    value["emulator"] = serde_json::to_value(&report)?;
    print_summary(
        &format!(
            "acquisition demo: {} s of emulated sensor over {path}",
            args.seconds
        ),
        &value,
        args.json,
    );
    if !args.json {
        println!("  recording          {} ({rows} rows)", args.out.display());
    }
    if summary.samples == 0 {
        bail!("no sample arrived over {path}");
    }
    Ok(())
}

async fn replay(args: ReplayArgs) -> Result<()> {
    let recording = crackbot_recording::read_csv(&args.file)?;
    let speed = if args.unpaced {
        ReplaySpeed::Unpaced
    } else if args.speed.is_finite() && args.speed > 0.0 {
        ReplaySpeed::Factor(args.speed)
    } else {
        bail!("--speed must be a positive factor, got {}", args.speed)
    };
    let mut replay = Replay::new(&recording, speed);
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        progress(Some(replay.remaining() as u64))
    };
    let mut summary = Summary::default();
    while let Some(sample) = replay.next().await {
        summary.add(&sample);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let value = summary.to_json(&LinkStats::default(), None);
    print_summary(
        &format!("replay of {}", args.file.display()),
        &value,
        args.json,
    );
    Ok(())
}

fn create_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating folder {}", dir.display()))?;
    }
    Ok(())
}

const EXAMPLE_CALIBRATION: &str = include_str!("../../acquisition/calibration/example.toml");
