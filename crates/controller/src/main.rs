//! `crackbot-sim-controller`: the simulated manipulator controller as its own process. It binds
//! the link's UDP port, talks to the robot at `--peer` with the pre-shared key of `--key`, streams
//! its state at 100 Hz, moves the simulated finger over the scene, and writes the simulated
//! sensor's 400 Hz frames into a new pseudo-terminal whose path it prints (`PTY /dev/pts/N`), so
//! `crackbot-robot` sees exactly what it would see with hardware.

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use crackbot_controller::{ControllerClock, SensorStall, ServerConfig, SimController};
use crackbot_link::{FaultConfig, Key, Security};
use crackbot_sim::Scene;

/// The simulated manipulator controller.
#[derive(Debug, Parser)]
#[command(name = "crackbot-sim-controller", version, about)]
struct Cli {
    /// Scene file (default: the built-in default scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// UDP address to listen on.
    #[arg(long, default_value = "127.0.0.1:7700")]
    bind: SocketAddr,
    /// The robot's UDP address.
    #[arg(long, default_value = "127.0.0.1:7701")]
    peer: SocketAddr,
    /// Pre-shared key file (64–128 hex digits, mode 0600).
    #[arg(long)]
    key: PathBuf,
    /// The link's id, the same on both ends (the wire format's §1: a packet of another link is
    /// refused).
    #[arg(long, default_value_t = 1)]
    link_id: u16,
    /// Folder of the controller's epoch counter (kept across restarts).
    #[arg(long, default_value = "out/controller")]
    state_dir: PathBuf,
    /// Simulate this many times faster than real time.
    #[arg(long, default_value_t = 1.0)]
    speedup: f64,
    /// Seed of the simulated sensor's noise.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Clock offset of the controller, µs.
    #[arg(long, default_value_t = 0.0)]
    clock_offset_us: f64,
    /// Clock drift of the controller, ppm.
    #[arg(long, default_value_t = 0.0)]
    clock_drift_ppm: f64,
    /// Fault: probability that an outgoing packet is lost.
    #[arg(long, default_value_t = 0.0)]
    loss: f64,
    /// Fault: probability that an outgoing packet is delayed past the next one.
    #[arg(long, default_value_t = 0.0)]
    reorder: f64,
    /// Fault: probability that an outgoing packet is sent twice.
    #[arg(long, default_value_t = 0.0)]
    duplicate: f64,
    /// Fault: fixed delay of outgoing packets, ms.
    #[arg(long, default_value_t = 0.0)]
    delay_ms: f64,
    /// Fault: the sensor stream stalls for 1 s during this slide (1-based).
    #[arg(long)]
    stall_slide: Option<u32>,
    /// Fault: restart (new epoch, arm stopped) this many seconds after starting.
    #[arg(long)]
    restart_after_s: Option<f64>,
    /// Stop after this many seconds (default: until Ctrl-C).
    #[arg(long)]
    seconds: Option<f64>,
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .init();
    let cli = Cli::parse();
    let scene = Scene::load_or_default(cli.scene.as_deref())?;
    let key = Key::from_file(&cli.key).with_context(|| "the link key")?;
    std::fs::create_dir_all(&cli.state_dir)
        .with_context(|| format!("creating {}", cli.state_dir.display()))?;
    let mut config = ServerConfig::new(
        scene,
        Security::Signed(key),
        cli.state_dir.join("controller.epoch"),
    );
    config.seed = cli.seed;
    config.link_id = cli.link_id;
    config.clock = ControllerClock {
        speedup: cli.speedup,
        offset_us: cli.clock_offset_us,
        drift_ppm: cli.clock_drift_ppm,
    };
    if cli.loss > 0.0 || cli.reorder > 0.0 || cli.duplicate > 0.0 || cli.delay_ms > 0.0 {
        config.faults.link = Some(FaultConfig {
            drop: cli.loss,
            reorder: cli.reorder,
            duplicate: cli.duplicate,
            delay: Duration::from_secs_f64(cli.delay_ms.max(0.0) / 1e3),
            ..FaultConfig::default()
        });
    }
    config.faults.stall = cli.stall_slide.map(|slide| SensorStall {
        slide,
        duration: Duration::from_secs(1),
    });
    config.faults.restart_after = cli.restart_after_s.map(Duration::from_secs_f64);
    let socket = UdpSocket::bind(cli.bind).with_context(|| format!("binding {}", cli.bind))?;
    let controller = SimController::spawn(config, socket, cli.peer)?;
    {
        // Whoever started us may close our output; the controller goes on regardless.
        use std::io::Write;
        let mut out = std::io::stdout();
        let _ = writeln!(out, "PTY {}", controller.sensor_path());
        let _ = writeln!(out, "LINK {}", controller.addr());
        let _ = out.flush();
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))?;
    }
    let end = cli
        .seconds
        .map(|s| std::time::Instant::now() + Duration::from_secs_f64(s));
    while !stop.load(Ordering::Relaxed) && end.is_none_or(|e| std::time::Instant::now() < e) {
        std::thread::sleep(Duration::from_millis(50));
    }
    let report = controller.shutdown()?;
    eprintln!(
        "controller: {} commands accepted, {} refused, {} slides done, {} states sent, {} watchdog stops, {} restarts",
        report.accepted,
        report.refused,
        report.slides_done,
        report.states_sent,
        report.watchdog_stops,
        report.restarts
    );
    Ok(())
}
