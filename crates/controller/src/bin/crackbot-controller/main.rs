//! `crackbot-controller`: the manipulator controller as its own process. It binds the link's
//! UDP port, talks to the robot at `--peer` with the pre-shared key of `--key`, streams its
//! state at 100 Hz and drives an arm:
//!
//! * `--arm sim` (default): the simulated finger over a scene, its simulated sensor's 400 Hz
//!   frames written into a new pseudo-terminal whose path it prints (`PTY /dev/pts/N`), so
//!   `crackbot-robot` sees exactly what it would see with hardware.
//! * `--arm ros2` (feature `ros2`): a ROS 2 arm over DDS (`crates/controller/docs/ros2.md`), the
//!   plate's frame from `--site`; `--sim-finger` adds a simulated finger and sensor that follow
//!   the pose the arm reports (its PTY printed likewise).
//!
//! `crackbot-controller register` finds the plate's frame in the arm's base frame from touched
//! points and writes it to the site file.

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};
use crackbot_controller::{
    ControllerClock, Faults, LinkServer, LinkSettings, SensorStall, ServerConfig, ServerReport,
    SimController,
};
use crackbot_link::{FaultConfig, Key, Security};
use crackbot_sim::Scene;

mod register;

/// The manipulator controller.
#[derive(Debug, Parser)]
#[command(name = "crackbot-controller", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    serve: Serve,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Find the plate's plane and frame in the arm's base frame from touched points, and write it
    /// to the site file's [surface] table.
    Register(register::Register),
}

/// Which arm the controller drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ArmKind {
    /// The simulated arm and finger over a scene.
    Sim,
    /// A ROS 2 arm over DDS (needs the `ros2` feature).
    Ros2,
}

#[derive(Debug, clap::Args)]
struct Serve {
    /// The arm to drive.
    #[arg(long, value_enum, default_value = "sim")]
    arm: ArmKind,
    /// Scene file (default: the built-in default scene): the simulated arm's, or the plate under
    /// the simulated finger of `--sim-finger`.
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
    key: Option<PathBuf>,
    /// The link's id, the same on both ends (the wire format's §1: a packet of another link is
    /// refused).
    #[arg(long, default_value_t = 1)]
    link_id: u16,
    /// Folder of the controller's epoch counter (kept across restarts).
    #[arg(long, default_value = "out/controller")]
    state_dir: PathBuf,
    /// `--arm ros2`: the ROS 2 configuration file (topics, frames, rates; default: the spec's
    /// defaults).
    #[arg(long)]
    ros2_config: Option<PathBuf>,
    /// `--arm ros2`: the site file (its [arm] limits and registered [surface]).
    #[arg(long)]
    site: Option<PathBuf>,
    /// `--arm ros2`: a simulated finger and sensor over `--scene` following the arm's pose.
    #[arg(long)]
    sim_finger: bool,
    /// Print the ROS 2 configuration's defaults (TOML) and exit.
    #[arg(long)]
    print_ros2_config: bool,
    /// Simulate this many times faster than real time (`--arm sim`).
    #[arg(long, default_value_t = 1.0)]
    speedup: f64,
    /// Seed of the simulated sensor's noise.
    #[arg(long, default_value_t = 7)]
    seed: u64,
    /// Clock offset of the controller, µs (`--arm sim`).
    #[arg(long, default_value_t = 0.0)]
    clock_offset_us: f64,
    /// Clock drift of the controller, ppm (`--arm sim`).
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
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| {
                "info,rustdds=warn,ros2_client=warn,ros2_client::distributions=error".into()
            }),
        )
        .init();
    let cli = Cli::parse();
    match cli.command {
        Some(Command::Register(r)) => register::run(&r),
        None => serve(&cli.serve),
    }
}

fn faults(cli: &Serve) -> Faults {
    let mut f = Faults::default();
    if cli.loss > 0.0 || cli.reorder > 0.0 || cli.duplicate > 0.0 || cli.delay_ms > 0.0 {
        f.link = Some(FaultConfig {
            drop: cli.loss,
            reorder: cli.reorder,
            duplicate: cli.duplicate,
            delay: Duration::from_secs_f64(cli.delay_ms.max(0.0) / 1e3),
            ..FaultConfig::default()
        });
    }
    f.stall = cli.stall_slide.map(|slide| SensorStall {
        slide,
        duration: Duration::from_secs(1),
    });
    f.restart_after = cli.restart_after_s.map(Duration::from_secs_f64);
    f
}

/// The link settings every arm shares.
fn link_settings(cli: &Serve) -> Result<LinkSettings> {
    let key_path = cli
        .key
        .as_ref()
        .context("--key FILE is needed: the link's pre-shared key")?;
    let key = Key::from_file(key_path).with_context(|| "the link key")?;
    std::fs::create_dir_all(&cli.state_dir)
        .with_context(|| format!("creating {}", cli.state_dir.display()))?;
    let mut link = LinkSettings::new(
        Security::Signed(key),
        cli.state_dir.join("controller.epoch"),
    );
    link.link_id = cli.link_id;
    link.faults = faults(cli);
    Ok(link)
}

/// Prints the lines whoever started the process reads (the PTY first).
fn announce(pty: Option<&str>, addr: SocketAddr) {
    // Whoever started us may close our output; the controller goes on regardless.
    use std::io::Write;
    let mut out = std::io::stdout();
    if let Some(p) = pty {
        let _ = writeln!(out, "PTY {p}");
    }
    let _ = writeln!(out, "LINK {addr}");
    let _ = out.flush();
}

/// Waits for Ctrl-C or `--seconds`.
fn wait(cli: &Serve) -> Result<()> {
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = stop.clone();
        ctrlc::set_handler(move || stop.store(true, Ordering::Relaxed))?;
    }
    let end = cli
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    while !stop.load(Ordering::Relaxed) && end.is_none_or(|e| Instant::now() < e) {
        std::thread::sleep(Duration::from_millis(50));
    }
    Ok(())
}

fn print_report(report: &ServerReport) {
    eprintln!(
        "controller: {} commands accepted, {} refused, {} slides done, {} states sent, {} watchdog stops, {} restarts",
        report.accepted,
        report.refused,
        report.slides_done,
        report.states_sent,
        report.watchdog_stops,
        report.restarts
    );
}

fn serve(cli: &Serve) -> Result<()> {
    if cli.print_ros2_config {
        let text = toml::to_string(&crackbot_controller::ros2::config::Ros2Config::default())?;
        print!("{text}");
        return Ok(());
    }
    let link = link_settings(cli)?;
    let socket = UdpSocket::bind(cli.bind).with_context(|| format!("binding {}", cli.bind))?;
    match cli.arm {
        ArmKind::Sim => serve_sim(cli, link, socket),
        ArmKind::Ros2 => serve_ros2(cli, link, socket),
    }
}

fn serve_sim(cli: &Serve, link: LinkSettings, socket: UdpSocket) -> Result<()> {
    let scene = Scene::load_or_default(cli.scene.as_deref())?;
    let mut config = ServerConfig::new(scene, link.security.clone(), link.epoch_file.clone());
    config.seed = cli.seed;
    config.link_id = link.link_id;
    config.faults = link.faults;
    config.clock = ControllerClock {
        speedup: cli.speedup,
        offset_us: cli.clock_offset_us,
        drift_ppm: cli.clock_drift_ppm,
    };
    let controller = SimController::spawn(&config, socket, cli.peer)?;
    announce(Some(controller.sensor_path()), controller.addr());
    wait(cli)?;
    print_report(&controller.shutdown()?);
    Ok(())
}

#[cfg(not(feature = "ros2"))]
fn serve_ros2(_: &Serve, _: LinkSettings, _: UdpSocket) -> Result<()> {
    anyhow::bail!(
        "this crackbot-controller was built without the ROS 2 arm: build it with `--features ros2`"
    )
}

#[cfg(feature = "ros2")]
fn serve_ros2(cli: &Serve, link: LinkSettings, socket: UdpSocket) -> Result<()> {
    use crackbot_controller::ros2::{config::Ros2Config, site, Ros2Arm};
    use crackbot_controller::sim::follow::FollowingSource;
    use crackbot_controller::sim::world::{Pressed, World};
    use crackbot_controller::SimSensor;

    let config = match &cli.ros2_config {
        Some(p) => Ros2Config::load(p)?,
        None => Ros2Config::default(),
    };
    let site_path = cli.site.as_ref().context(
        "--arm ros2 needs --site FILE (the arm's [arm] limits and the registered [surface])",
    )?;
    let site = site::load(site_path)?;
    let arm = Ros2Arm::spawn(config, site.limits, site.surface)?;
    let sensor = if cli.sim_finger {
        let scene = Scene::load_or_default(cli.scene.as_deref())?;
        let world = World::new(&scene, cli.seed)?;
        let mut follow = arm.follower();
        let source = FollowingSource::new(world, move || {
            follow().map(|(pose, on)| {
                let pressed = on.map(|s| Pressed {
                    start: s.start,
                    end: s.end,
                    speed_mm_s: s.speed_mm_s,
                });
                (pose, pressed)
            })
        });
        Some(SimSensor::spawn_with(source, 1.0)?)
    } else {
        None
    };
    let server = LinkServer::spawn(arm, link, socket, cli.peer)?;
    announce(sensor.as_ref().map(SimSensor::path), server.addr());
    wait(cli)?;
    print_report(&server.shutdown()?);
    if let Some(s) = sensor {
        s.stop()?;
    }
    Ok(())
}
