//! The controller's side of the link, for any [`Arm`]: commands in, checked
//! ([`crate::command::check`]) against the arm's limits and clock, acknowledgements, refusals by
//! field and the 100 Hz state stream out, over the authenticated UDP link (`crackbot-link`).
//!
//! A watchdog stops the arm when the host goes silent (no message for
//! [`LinkSettings::watchdog`]) while it moves. Fault injection: the link's own packet faults
//! ([`FaultConfig`]: loss, delay, reordering, duplication), the sensor stream stalling
//! mid-slide (an arm with a simulated sensor, [`Arm::stall_sensor`]), and the controller
//! restarting (the arm stops, the link comes back with a new epoch, as after a power cycle).

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crackbot_link::{
    EpochSource, ErrorCode, ErrorReport, FaultConfig, FaultInjector, LinkConfig, LinkEndpoint,
    LinkError, LinkStats, Message, Pose, Security, State, Velocity,
};
use serde::Serialize;

use crate::arm::{Arm, ArmState, Mode};
use crate::command::check;
use crate::limits::Refusal;

/// Errors of a controller.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ControllerError {
    /// The scene or the simulator failed.
    #[cfg(feature = "sim")]
    #[error(transparent)]
    Sim(#[from] crackbot_sim::SimError),
    /// The emulated sensor failed.
    #[cfg(feature = "sim")]
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
    /// The arm could not be started.
    #[error("the arm: {0}")]
    Arm(String),
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

/// The link side's settings, whatever the arm.
#[derive(Debug, Clone)]
pub struct LinkSettings {
    /// Link security (the pre-shared key).
    pub security: Security,
    /// Where the controller keeps its epoch counter (survives restarts).
    pub epoch_file: PathBuf,
    /// Link id.
    pub link_id: u16,
    /// State messages per second of wall time (100–1000).
    pub state_rate_hz: f64,
    /// Stop the arm when the host has been silent this long while the arm moves.
    pub watchdog: Duration,
    /// Faults to inject.
    pub faults: Faults,
}

impl LinkSettings {
    /// Defaults: 100 Hz state stream, 1 s watchdog, link 1, no faults.
    pub fn new(security: Security, epoch_file: impl Into<PathBuf>) -> Self {
        LinkSettings {
            security,
            epoch_file: epoch_file.into(),
            link_id: 1,
            state_rate_hz: 100.0,
            watchdog: Duration::from_secs(1),
            faults: Faults::default(),
        }
    }

    fn check(&self) -> Result<(), ControllerError> {
        if !(self.state_rate_hz.is_finite() && (100.0..=1000.0).contains(&self.state_rate_hz)) {
            return Err(ControllerError::Setting {
                field: "state_rate_hz",
                value: self.state_rate_hz,
                allowed: "[100, 1000] Hz",
            });
        }
        Ok(())
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

/// The link side running in its own thread over an arm.
#[derive(Debug)]
pub struct LinkServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<ServerReport, ControllerError>>>,
}

impl LinkServer {
    /// Serves `arm` on `socket` (already bound: its address is the one the host talks to) to the
    /// host at `host`, from a new thread.
    pub fn spawn<A: Arm + 'static>(
        arm: A,
        settings: LinkSettings,
        socket: UdpSocket,
        host: SocketAddr,
    ) -> Result<LinkServer, ControllerError> {
        settings.check()?;
        let addr = socket.local_addr()?;
        let link_config = LinkConfig::controller(
            settings.security.clone(),
            EpochSource::File(settings.epoch_file.clone()),
        )
        .with_link_id(settings.link_id);
        let endpoint = open(socket, host, link_config.clone(), &settings.faults)?;
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let stop = stop.clone();
            std::thread::Builder::new()
                .name("controller link".into())
                .spawn(move || {
                    let mut arm = arm;
                    let link = Served {
                        host,
                        link_config: &link_config,
                        settings: &settings,
                    };
                    serve(endpoint, &link, &mut arm, &stop)
                })?
        };
        Ok(LinkServer {
            addr,
            stop,
            thread: Some(thread),
        })
    }

    /// The controller's UDP address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Whether the link thread has ended (an error, or a stop).
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// Stops the link side (the arm stops first) and returns its report.
    pub fn shutdown(mut self) -> Result<ServerReport, ControllerError> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(t) => t.join().map_err(|_| ControllerError::Panicked)?,
            None => Err(ControllerError::Panicked),
        }
    }
}

impl Drop for LinkServer {
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
    faults: &Faults,
) -> Result<LinkEndpoint, ControllerError> {
    let mut ep = LinkEndpoint::from_socket(socket, host, link)?;
    if let Some(f) = &faults.link {
        ep.set_fault_injector(Some(FaultInjector::new(f.clone())));
    }
    Ok(ep)
}

/// Whether the arm is a third of the way through slide `id`, in contact.
fn mid_slide(state: Option<ArmState>, id: u32) -> bool {
    state.is_some_and(|t| t.mode == Mode::Sliding(id) && t.pose[2] <= 0.0 && t.progress >= 0.3)
}

/// The link's code for a refusal by the arm.
pub fn refusal_code(r: &Refusal) -> ErrorCode {
    match r {
        Refusal::OutsideWorkspace { .. } => ErrorCode::OutsideWorkspace,
        Refusal::OverSpeed { .. } => ErrorCode::OverSpeedLimit,
        Refusal::OutOfRange { .. } => ErrorCode::InvalidCommand,
        Refusal::Faulted(_) => ErrorCode::Faulted,
    }
}

/// The state message of an arm's state (a fault, when the arm reports one, is the mode).
pub fn state_message(s: &ArmState, fault: Option<u16>) -> State {
    let f = |v: f64| v as f32;
    State {
        controller_time_us: s.time_us,
        pose: Pose {
            x_mm: f(s.pose[0]),
            y_mm: f(s.pose[1]),
            z_mm: f(s.pose[2]),
        },
        velocity: Velocity {
            x_mm_s: f(s.velocity[0]),
            y_mm_s: f(s.velocity[1]),
            z_mm_s: f(s.velocity[2]),
        },
        mode: match fault {
            Some(code) => crackbot_link::Mode::Fault { code },
            None => s.mode.to_link(),
        },
        slide_progress: f(s.progress),
    }
}

/// What the serving loop needs besides the arm.
struct Served<'a> {
    host: SocketAddr,
    link_config: &'a LinkConfig,
    settings: &'a LinkSettings,
}

/// Fault injections still to come.
#[derive(Debug, Default)]
struct Pending {
    restarted: bool,
    slides_started: u32,
    stall: Option<u32>,
    restart: Option<u32>,
}

/// Whether an injected restart is due.
fn restart_due<A: Arm>(arm: &A, faults: &Faults, pending: &Pending, started: Instant) -> bool {
    !pending.restarted
        && (faults.restart_after.is_some_and(|a| started.elapsed() >= a)
            || pending.restart.is_some_and(|id| mid_slide(arm.state(), id)))
}

/// An injected restart: the arm stops, the link comes back with a new epoch on the same port.
fn restart<A: Arm>(
    ep: LinkEndpoint,
    link: &Served<'_>,
    arm: &mut A,
) -> Result<LinkEndpoint, ControllerError> {
    arm.stop();
    let addr = ep.local_addr();
    drop(ep);
    std::thread::sleep(Duration::from_millis(200));
    let socket = UdpSocket::bind(addr)?;
    let ep = open(
        socket,
        link.host,
        link.link_config.clone(),
        &link.settings.faults,
    )?;
    tracing::warn!("controller restarted (injected)");
    Ok(ep)
}

/// Handles one command: checks it, hands it to the arm, and schedules the injections tied to
/// the slide it starts. `None`: accepted; `Some`: the refusal to send back.
fn handle<A: Arm>(
    arm: &mut A,
    message: &Message,
    seq: u32,
    faults: &Faults,
    pending: &mut Pending,
) -> Option<ErrorReport> {
    let outcome = check(message, &arm.limits(), arm.now_us()).map(|c| arm.apply(c));
    match outcome {
        Ok(Ok(Some(id))) => {
            pending.slides_started += 1;
            if faults
                .stall
                .is_some_and(|st| st.slide == pending.slides_started)
            {
                pending.stall = Some(id);
            }
            if faults.restart_during_slide == Some(pending.slides_started) {
                pending.restart = Some(id);
            }
            None
        }
        Ok(Ok(None)) => None,
        Ok(Err(refusal)) => Some(ErrorReport::new(
            seq,
            refusal_code(&refusal),
            &refusal.to_string(),
        )),
        Err(e) => Some(e.report(seq)),
    }
}

/// Sends the state and the finished slides, after the watchdog had its say.
fn stream_state<A: Arm>(
    ep: &mut LinkEndpoint,
    arm: &mut A,
    silent_for: Duration,
    watchdog: Duration,
    report: &mut ServerReport,
) -> Result<(), ControllerError> {
    if arm.is_busy() && silent_for > watchdog {
        arm.stop();
        report.watchdog_stops += 1;
        tracing::warn!("host silent for {watchdog:?}: arm stopped");
    }
    let finished = arm.take_finished();
    if let Some(state) = arm.state() {
        let fault = arm.fault().map(|(code, _)| code);
        ep.send_unreliable(&Message::State(state_message(&state, fault)))?;
        report.states_sent += 1;
    }
    for id in finished {
        report.slides_done += 1;
        // Reliable: the host must learn that the slide ended even when packets are lost.
        if let Err(e) = ep.send_reliable(&Message::Done { slide_id: id }) {
            tracing::warn!("slide {id} done, not acknowledged: {e}");
        }
    }
    Ok(())
}

fn serve<A: Arm>(
    mut ep: LinkEndpoint,
    link: &Served<'_>,
    arm: &mut A,
    stop: &AtomicBool,
) -> Result<ServerReport, ControllerError> {
    let settings = link.settings;
    let mut report = ServerReport::default();
    let period = Duration::from_secs_f64(1.0 / settings.state_rate_hz);
    let started = Instant::now();
    let mut next_state = Instant::now();
    let mut last_heard = Instant::now();
    let mut pending = Pending::default();
    while !stop.load(Ordering::Relaxed) {
        if restart_due(arm, &settings.faults, &pending, started) {
            pending.restarted = true;
            ep = restart(ep, link, arm)?;
            report.restarts += 1;
        }
        if let Some(id) = pending.stall {
            if mid_slide(arm.state(), id) {
                pending.stall = None;
                if let Some(s) = settings.faults.stall {
                    arm.stall_sensor(s.duration);
                    tracing::warn!("sensor stalled for {:?} (injected)", s.duration);
                }
            }
        }
        let wait = next_state.saturating_duration_since(Instant::now());
        if let Some(r) = ep.recv(wait.min(Duration::from_millis(5)))? {
            last_heard = Instant::now();
            match handle(arm, &r.message, r.seq, &settings.faults, &mut pending) {
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
        // Behind by a few periods (a busy host), the stream catches up to keep its rate; further
        // behind, it starts afresh rather than sending a burst.
        next_state += period;
        if next_state + 5 * period < Instant::now() {
            next_state = Instant::now() + period;
        }
        stream_state(
            &mut ep,
            arm,
            last_heard.elapsed(),
            settings.watchdog,
            &mut report,
        )?;
    }
    arm.stop();
    report.link = ep.stats();
    Ok(report)
}
