//! The controller's side of the link: commands in, acknowledgements, refusals and the 100 Hz
//! state stream out, over the authenticated UDP link (`crackbot-link`).
//!
//! A watchdog stops the arm when the host goes silent (no message for
//! [`ServerConfig::watchdog`]) while it moves. Fault injection: the link's own packet faults
//! ([`FaultConfig`]: loss, delay, reordering, duplication), the sensor stream stalling
//! mid-slide, and the controller restarting (the arm stops, the link comes back with a new
//! epoch, as after a power cycle).

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crackbot_link::{
    EpochSource, ErrorCode, ErrorReport, FaultConfig, FaultInjector, LinkConfig, LinkEndpoint,
    LinkError, LinkStats, Message, Pose, Security, State, Velocity,
};
use crackbot_sim::Scene;
use serde::Serialize;

use crate::command::check;
use crate::limits::Refusal;
use crate::sensor::{lock, Shared, SharedWorld, SimSensor};
use crate::world::{Mode, World};
use crate::ControllerClock;

/// Errors of the simulated controller.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ControllerError {
    /// The scene or the simulator failed.
    #[error(transparent)]
    Sim(#[from] crackbot_sim::SimError),
    /// The emulated sensor failed.
    #[error(transparent)]
    Emulator(#[from] crackbot_emulator::EmulatorError),
    /// The link failed.
    #[error("link: {0}")]
    Link(#[from] LinkError),
    /// A socket failed.
    #[error("controller socket: {0}")]
    Io(#[from] std::io::Error),
    /// A setting is out of range.
    #[error("the setting {field} = {value} is outside {allowed}")]
    Setting {
        /// Which.
        field: &'static str,
        /// The value given.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// The controller thread panicked.
    #[error("the controller thread panicked")]
    Panicked,
}

/// Faults to inject.
#[derive(Debug, Clone, Default)]
pub struct Faults {
    /// Packet faults on the controller's outgoing packets.
    pub link: Option<FaultConfig>,
    /// Stall the sensor stream for this long, starting this far into the `n`-th slide (1-based).
    pub stall: Option<SensorStall>,
    /// Restart the controller once, this long after it started.
    pub restart_after: Option<Duration>,
    /// Restart the controller once, a third of the way through this slide (1-based).
    pub restart_during_slide: Option<u32>,
}

/// A sensor stall.
#[derive(Debug, Clone, Copy)]
pub struct SensorStall {
    /// The slide (1-based count of slides started) during which it happens.
    pub slide: u32,
    /// How long the line stays silent.
    pub duration: Duration,
}

/// Settings of the simulated controller.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// The scene the arm works over.
    pub scene: Scene,
    /// Seed of the sensor's noise.
    pub seed: u64,
    /// Link security (the pre-shared key).
    pub security: Security,
    /// Where the controller keeps its epoch counter (survives restarts).
    pub epoch_file: PathBuf,
    /// Link id.
    pub link_id: u16,
    /// The controller's clock (offset, drift, speed-up).
    pub clock: ControllerClock,
    /// State messages per second of wall time (≥ 100).
    pub state_rate_hz: f64,
    /// Stop the arm when the host has been silent this long while the arm moves.
    pub watchdog: Duration,
    /// Faults to inject.
    pub faults: Faults,
}

impl ServerConfig {
    /// Defaults: 100 Hz state stream, 1 s watchdog, link 1, real time, no faults.
    pub fn new(scene: Scene, security: Security, epoch_file: impl Into<PathBuf>) -> Self {
        ServerConfig {
            scene,
            seed: 7,
            security,
            epoch_file: epoch_file.into(),
            link_id: 1,
            clock: ControllerClock::default(),
            state_rate_hz: 100.0,
            watchdog: Duration::from_secs(1),
            faults: Faults::default(),
        }
    }
}

/// What the controller did, for its report.
#[derive(Debug, Clone, Default, Serialize)]
pub struct ServerReport {
    /// Commands accepted.
    pub accepted: u64,
    /// Commands refused (outside the workspace, over the limits, invalid).
    pub refused: u64,
    /// Slides completed.
    pub slides_done: u64,
    /// State messages sent.
    pub states_sent: u64,
    /// Times the watchdog stopped the arm.
    pub watchdog_stops: u64,
    /// Restarts injected.
    pub restarts: u64,
    /// The link's counters (of the last epoch).
    #[serde(skip)]
    pub link: LinkStats,
}

/// The simulated controller running in this process: its sensor thread and its link thread.
#[derive(Debug)]
pub struct SimController {
    sensor: Option<SimSensor>,
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<ServerReport, ControllerError>>>,
    shared: SharedWorld,
}

impl SimController {
    /// Starts the controller on `socket` (already bound: its address is the one the host talks
    /// to), talking to the host at `host`.
    pub fn spawn(
        config: ServerConfig,
        socket: UdpSocket,
        host: SocketAddr,
    ) -> Result<SimController, ControllerError> {
        if !(config.state_rate_hz.is_finite() && (100.0..=1000.0).contains(&config.state_rate_hz)) {
            return Err(ControllerError::Setting {
                field: "state_rate_hz",
                value: config.state_rate_hz,
                allowed: "[100, 1000] Hz",
            });
        }
        let world = World::new(&config.scene, config.seed)?;
        let shared: SharedWorld = Arc::new(Mutex::new(Shared {
            world,
            last: None,
            finished: Vec::new(),
            fault: None,
        }));
        let sensor = SimSensor::spawn(shared.clone(), config.clock.speedup)?;
        let addr = socket.local_addr()?;
        let link_config = LinkConfig::controller(
            config.security.clone(),
            EpochSource::File(config.epoch_file.clone()),
        )
        .with_link_id(config.link_id);
        let endpoint = open(socket, host, link_config.clone(), &config)?;
        let stop = Arc::new(AtomicBool::new(false));
        let control = sensor.control();
        let thread = {
            let stop = stop.clone();
            let shared = shared.clone();
            std::thread::Builder::new()
                .name("sim-controller link".into())
                .spawn(move || {
                    serve(
                        endpoint,
                        host,
                        &link_config,
                        &config,
                        &shared,
                        &stop,
                        &control,
                    )
                })?
        };
        Ok(SimController {
            sensor: Some(sensor),
            addr,
            stop,
            thread: Some(thread),
            shared,
        })
    }

    /// The sensor's pseudo-terminal (open it as the robot's serial port).
    pub fn sensor_path(&self) -> &str {
        self.sensor.as_ref().map_or("", |s| s.path())
    }

    /// The controller's UDP address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The arm's true pose now (ground truth for tests), mm.
    pub fn true_pose(&self) -> [f64; 3] {
        lock(&self.shared).world.pose()
    }

    /// Stops the controller and its sensor and returns its report.
    pub fn shutdown(mut self) -> Result<ServerReport, ControllerError> {
        self.stop.store(true, Ordering::Relaxed);
        let report = match self.thread.take() {
            Some(t) => t.join().map_err(|_| ControllerError::Panicked)?,
            None => Err(ControllerError::Panicked),
        };
        if let Some(s) = self.sensor.take() {
            s.stop()?;
        }
        report
    }
}

impl Drop for SimController {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn open(
    socket: UdpSocket,
    host: SocketAddr,
    link: LinkConfig,
    config: &ServerConfig,
) -> Result<LinkEndpoint, ControllerError> {
    let mut ep = LinkEndpoint::from_socket(socket, host, link)?;
    if let Some(f) = &config.faults.link {
        ep.set_fault_injector(Some(FaultInjector::new(f.clone())));
    }
    Ok(ep)
}

/// Whether slide `id` is a third of the way through its stroke.
fn mid_slide(shared: &SharedWorld, id: u32) -> bool {
    lock(shared)
        .last
        .is_some_and(|t| t.mode == Mode::Sliding(id) && t.pose[2] == 0.0 && t.progress >= 0.3)
}

fn to_link_mode(mode: Mode) -> crackbot_link::Mode {
    match mode {
        Mode::Idle => crackbot_link::Mode::Idle,
        Mode::Moving => crackbot_link::Mode::Moving,
        Mode::Sliding(id) => crackbot_link::Mode::Sliding { id },
        Mode::Stopped => crackbot_link::Mode::Stopped,
    }
}

fn refusal_code(r: &Refusal) -> ErrorCode {
    match r {
        Refusal::OutsideWorkspace { .. } => ErrorCode::OutsideWorkspace,
        Refusal::OverSpeed { .. } => ErrorCode::OverSpeedLimit,
        Refusal::OutOfRange { .. } => ErrorCode::InvalidCommand,
        Refusal::Faulted(_) => ErrorCode::Faulted,
    }
}

fn serve(
    mut ep: LinkEndpoint,
    host: SocketAddr,
    link_config: &LinkConfig,
    config: &ServerConfig,
    shared: &SharedWorld,
    stop: &AtomicBool,
    control: &crate::sensor::SensorControl,
) -> Result<ServerReport, ControllerError> {
    let mut report = ServerReport::default();
    let period = Duration::from_secs_f64(1.0 / config.state_rate_hz);
    let started = Instant::now();
    let mut next_state = Instant::now();
    let mut last_heard = Instant::now();
    let mut restarted = false;
    let mut slides_started = 0u32;
    let mut stall_pending: Option<u32> = None;
    let mut restart_pending: Option<u32> = None;
    while !stop.load(Ordering::Relaxed) {
        // Injected restart: the arm stops, the link comes back with a new epoch.
        let restart_now = !restarted
            && (config
                .faults
                .restart_after
                .is_some_and(|a| started.elapsed() >= a)
                || restart_pending.is_some_and(|id| mid_slide(shared, id)));
        if restart_now {
            restarted = true;
            report.restarts += 1;
            lock(shared).world.stop();
            let addr = ep.local_addr();
            drop(ep);
            std::thread::sleep(Duration::from_millis(200));
            let socket = UdpSocket::bind(addr)?;
            ep = open(socket, host, link_config.clone(), config)?;
            tracing::warn!("controller restarted (injected)");
        }
        if let Some(id) = stall_pending {
            // Mid-slide: once a third of the stroke is done.
            if mid_slide(shared, id) {
                stall_pending = None;
                if let Some(s) = config.faults.stall {
                    control.stall_for(s.duration);
                    tracing::warn!("sensor stalled for {:?} (injected)", s.duration);
                }
            }
        }
        let wait = next_state.saturating_duration_since(Instant::now());
        if let Some(r) = ep.recv(wait.min(Duration::from_millis(5)))? {
            last_heard = Instant::now();
            let outcome = {
                let mut s = lock(shared);
                let now_us = config.clock.at_tick(s.world.tick_count());
                let limits = *s.world.limits();
                check(&r.message, &limits, now_us).map(|c| s.world.apply(c))
            };
            let refusal = match outcome {
                Ok(Ok(Some(id))) => {
                    slides_started += 1;
                    if config
                        .faults
                        .stall
                        .is_some_and(|st| st.slide == slides_started)
                    {
                        stall_pending = Some(id);
                    }
                    if config.faults.restart_during_slide == Some(slides_started) {
                        restart_pending = Some(id);
                    }
                    None
                }
                Ok(Ok(None)) => None,
                Ok(Err(refusal)) => Some(ErrorReport::new(
                    r.seq,
                    refusal_code(&refusal),
                    &refusal.to_string(),
                )),
                Err(e) => Some(e.report(r.seq)),
            };
            match refusal {
                Some(e) => {
                    report.refused += 1;
                    tracing::info!("refused: {}", e.text);
                    ep.send_reliable(&Message::Error(e)).ok();
                }
                None => report.accepted += 1,
            }
        }
        if Instant::now() < next_state {
            continue;
        }
        next_state += period;
        if next_state < Instant::now() {
            next_state = Instant::now() + period;
        }
        let (state, finished) = {
            let mut s = lock(shared);
            if s.world.is_busy() && last_heard.elapsed() > config.watchdog {
                s.world.stop();
                report.watchdog_stops += 1;
                tracing::warn!("host silent for {:?}: arm stopped", config.watchdog);
            }
            let finished = std::mem::take(&mut s.finished);
            let mode = if s.fault.is_some() {
                crackbot_link::Mode::Fault { code: 1 }
            } else {
                to_link_mode(s.world.mode())
            };
            let state = s.last.map(|t| State {
                controller_time_us: config.clock.at_tick(t.tick),
                pose: Pose {
                    x_mm: t.pose[0] as f32,
                    y_mm: t.pose[1] as f32,
                    z_mm: t.pose[2] as f32,
                },
                velocity: Velocity {
                    x_mm_s: t.velocity[0] as f32,
                    y_mm_s: t.velocity[1] as f32,
                    z_mm_s: t.velocity[2] as f32,
                },
                mode,
                slide_progress: t.progress as f32,
            });
            (state, finished)
        };
        if let Some(state) = state {
            ep.send_unreliable(&Message::State(state))?;
            report.states_sent += 1;
        }
        for id in finished {
            report.slides_done += 1;
            // Reliable: the host must learn that the slide ended even when packets are lost.
            if let Err(e) = ep.send_reliable(&Message::Done { slide_id: id }) {
                tracing::warn!("slide {id} done, not acknowledged: {e}");
            }
        }
    }
    lock(shared).world.stop();
    report.link = ep.stats();
    Ok(report)
}
