//! The simulated sensor: the world stepped by the emulated firmware's 400 Hz ticks, its frames
//! written into a new pseudo-terminal that the robot opens like the real board's serial port.
//!
//! ```text
//! World::step ─▶ SourceAdc ─▶ firmware (crackbot-firmware, on this host) ─▶ PTY ─▶ robot
//! ```
//!
//! A stall (the sensor stream stopping mid-slide, [`SensorControl::stall_for`]) silences the
//! line while the firmware and the world go on ticking, as a board whose USB link hangs would.

use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crackbot_emulator::{run, EmulatorConfig, EmulatorError, EmulatorReport, Pty, SignalSource};
use serialport::SerialPort as _;

use super::world::{Tick, World};

/// The world and what the last tick produced, shared by the sensor and link threads.
#[derive(Debug)]
pub struct Shared {
    /// The simulated arm and finger.
    pub world: World,
    /// The last tick's output.
    pub last: Option<Tick>,
    /// Slides finished since the link thread last looked.
    pub finished: Vec<u32>,
    /// A simulation failure, if one stopped the arm.
    pub fault: Option<String>,
}

/// A handle on the shared world.
pub type SharedWorld = Arc<Mutex<Shared>>;

/// Locks the shared world, recovering it if a thread panicked while holding it (the world's
/// state is still consistent between ticks).
pub fn lock(shared: &SharedWorld) -> MutexGuard<'_, Shared> {
    shared
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The world as the emulated board's analog front end: each sample is one world step.
struct WorldSource {
    shared: SharedWorld,
    last_counts: [f64; 4],
}

impl SignalSource for WorldSource {
    fn sample(&mut self, _t: f64) -> [f64; 4] {
        let mut s = lock(&self.shared);
        match s.world.step() {
            Ok(t) => {
                if let Some(id) = t.finished {
                    s.finished.push(id);
                }
                self.last_counts = t.counts;
                s.last = Some(t);
            }
            Err(e) => {
                tracing::error!("simulation failed, arm stopped: {e}");
                s.fault = Some(e.to_string());
            }
        }
        self.last_counts
    }
}

/// The line to the robot, silenced while a stall lasts.
struct StallableLine<W> {
    inner: W,
    stalled_until_us: Arc<AtomicU64>,
    start: Instant,
}

impl<W: Write> Write for StallableLine<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let now = self.start.elapsed().as_micros() as u64;
        if now < self.stalled_until_us.load(Ordering::Relaxed) {
            return Ok(buf.len());
        }
        match self.inner.write(buf) {
            // Nobody reads (the robot has not opened the port yet, or has gone): the board
            // streams regardless, and the bytes are lost, as on a real line.
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::TimedOut | std::io::ErrorKind::WouldBlock
                ) =>
            {
                Ok(buf.len())
            }
            other => other,
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Controls of a running sensor (fault injection).
#[derive(Debug, Clone)]
pub struct SensorControl {
    stalled_until_us: Arc<AtomicU64>,
    start: Instant,
}

impl SensorControl {
    /// Silences the line for `d` from now (frames are lost, as when a board's link hangs).
    pub fn stall_for(&self, d: Duration) {
        let until = (self.start.elapsed() + d).as_micros() as u64;
        self.stalled_until_us.store(until, Ordering::Relaxed);
    }
}

/// The emulated sensor streaming the world into a pseudo-terminal from its own thread.
#[derive(Debug)]
pub struct SimSensor {
    path: String,
    stop: Arc<AtomicBool>,
    control: SensorControl,
    thread: Option<JoinHandle<Result<EmulatorReport, EmulatorError>>>,
}

impl SimSensor {
    /// Starts the firmware ticking at 400 Hz × `speedup` (wall clock), each tick one world step.
    pub fn spawn(shared: SharedWorld, speedup: f64) -> Result<SimSensor, EmulatorError> {
        let source = WorldSource {
            shared,
            last_counts: [0.0; 4],
        };
        SimSensor::spawn_with(source, speedup)
    }

    /// Starts the firmware ticking at 400 Hz × `speedup` (wall clock), each tick one sample of
    /// `source`.
    pub fn spawn_with(
        source: impl SignalSource + Send + 'static,
        speedup: f64,
    ) -> Result<SimSensor, EmulatorError> {
        if !(speedup.is_finite() && (0.1..=50.0).contains(&speedup)) {
            return Err(EmulatorError::Config(format!(
                "speed-up {speedup} is not in [0.1, 50]"
            )));
        }
        let rate = crackbot_sim::run::SAMPLE_RATE_HZ * speedup;
        let config = EmulatorConfig {
            rate_hz: rate,
            // The line keeps up with the faster ticks (a PTY has no baud rate of its own).
            baud: (115_200.0 * speedup.max(1.0)).round() as u32,
            ..Default::default()
        };
        let pty = Pty::open()?;
        let path = pty.path().to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let control = SensorControl {
            stalled_until_us: Arc::new(AtomicU64::new(0)),
            start: Instant::now(),
        };
        let thread_stop = stop.clone();
        let thread_control = control.clone();
        let thread = std::thread::Builder::new()
            .name(format!("sim-sensor {path}"))
            .spawn(move || {
                let (mut master, slave) = pty.into_parts();
                // A board never waits for its reader: with the port's default timeout a write
                // into a full pseudo-terminal held each tick for 100 ms, and the world fell
                // behind while nobody read, then caught up in a burst.
                if let Err(e) = master.set_timeout(Duration::ZERO) {
                    tracing::warn!("the sensor's line keeps its write timeout: {e}");
                }
                let mut line = StallableLine {
                    inner: master,
                    stalled_until_us: thread_control.stalled_until_us.clone(),
                    start: thread_control.start,
                };
                let report = run(&config, source, &mut line, &thread_stop);
                std::thread::sleep(Duration::from_millis(200));
                drop(slave);
                report
            })
            .map_err(EmulatorError::Thread)?;
        Ok(SimSensor {
            path,
            stop,
            control,
            thread: Some(thread),
        })
    }

    /// The device the robot opens.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Fault injection.
    pub fn control(&self) -> SensorControl {
        self.control.clone()
    }

    /// Stops the sensor and returns the emulator's report.
    pub fn stop(mut self) -> Result<EmulatorReport, EmulatorError> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(t) => t.join().map_err(|_| EmulatorError::Panicked)?,
            None => Err(EmulatorError::Panicked),
        }
    }
}

impl Drop for SimSensor {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_sim::scene::Scene;

    /// Nobody reads the port (the robot has not opened it yet): the board streams regardless,
    /// its bytes are lost, and the world keeps its pace. A write that waited for a reader once
    /// held each tick for the port's 100 ms timeout; the world then fell behind and caught up
    /// in a burst when a reader arrived, so a mission ran its simulated seconds in milliseconds.
    #[test]
    fn an_unread_port_does_not_hold_the_world_back() {
        let world = World::new(&Scene::builtin_default(), 3).expect("default scene");
        let shared: SharedWorld = Arc::new(Mutex::new(Shared {
            world,
            last: None,
            finished: Vec::new(),
            fault: None,
        }));
        // 20 000 ticks per second fill the pseudo-terminal's buffer within a fraction of it.
        let speedup = 50.0;
        let sensor = SimSensor::spawn(shared.clone(), speedup).expect("sensor");
        let started = Instant::now();
        std::thread::sleep(Duration::from_secs(2));
        let ticks = lock(&shared).world.tick_count();
        let elapsed = started.elapsed().as_secs_f64();
        sensor.stop().expect("report");
        let expected = crackbot_sim::run::SAMPLE_RATE_HZ * speedup * elapsed;
        assert!(
            ticks as f64 > 0.8 * expected,
            "{ticks} world ticks in {elapsed:.2} s with nobody reading, expected about {expected:.0}"
        );
    }
}
