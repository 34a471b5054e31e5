//! `crackbot-sensor-emulator`: the sensor firmware running on the host, writing 400 Hz frames to
//! a serial device or to a new pseudo-terminal.
//!
//! ```text
//! crackbot-sensor-emulator --pty --duration 10          # prints "PTY /dev/pts/N", then streams
//! crackbot-sensor-emulator --port /dev/ttyUSB1 --baud 115200 --flip-rate 0.01
//! ```

use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{bail, Context, Result};
use clap::Parser;
use crackbot_emulator::{run, Corruption, EmulatorConfig, RecordingSource, SyntheticSlide};
use serialport::SerialPort;

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
    #[arg(long, required_unless_present = "pty")]
    port: Option<String>,
    /// UART baud rate (8N1). Frames need 92000 baud at 400 Hz; lower rates make the firmware drop
    /// frames and set the overrun flag, exactly as on the board.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 400.0)]
    rate: f64,
    /// Stop after this many seconds (default: run until interrupted).
    #[arg(long, conflicts_with = "frames")]
    duration: Option<f64>,
    /// Stop after this many ticks of the sample clock.
    #[arg(long)]
    frames: Option<u64>,
    /// Replay the D1, D2, D3, P columns of this CSV recording instead of the synthetic slide.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Crack width of the synthetic slide, mm (0 = flat).
    #[arg(long, default_value_t = 5.0)]
    crack_width: f64,
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
    let ticks = match (args.duration, args.frames) {
        (Some(d), _) if !(d.is_finite() && d >= 0.0) => {
            bail!("--duration must be a non-negative number of seconds, got {d}")
        }
        (Some(d), _) => Some((d * args.rate).round() as u64),
        (None, n) => n,
    };
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
    let (mut port, _slave): (Box<dyn SerialPort>, Option<Box<dyn SerialPort>>) = if args.pty {
        let (master, slave) =
            serialport::TTYPort::pair().context("creating a pseudo-terminal pair")?;
        let name = slave
            .name()
            .context("the pseudo-terminal has no device path")?;
        println!("PTY {name}");
        std::io::stdout().flush()?;
        (Box::new(master), Some(Box::new(slave)))
    } else {
        let path = args.port.clone().unwrap_or_default();
        if !std::path::Path::new(&path).exists() {
            bail!("serial device {path} does not exist");
        }
        let port = serialport::new(&path, args.baud)
            .timeout(Duration::from_secs(1))
            .open()
            .with_context(|| format!("opening serial device {path} at {} baud", args.baud))?;
        (port, None)
    };

    if args.wait_for_start {
        let mut line = String::new();
        std::io::stdin()
            .lock()
            .read_line(&mut line)
            .context("waiting for the start line on stdin")?;
    }

    let result = match &args.replay {
        Some(path) => {
            let rec = crackbot_recording::read_csv(path)?;
            let source = RecordingSource::new(rec)
                .with_context(|| format!("recording {} has no rows", path.display()))?;
            run(&config, source, &mut port, &stop)
        }
        None => {
            let mut source = SyntheticSlide::new(args.seed);
            source.crack_width_mm = args.crack_width;
            run(&config, source, &mut port, &stop)
        }
    };
    let report = result?;
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
    Ok(())
}
