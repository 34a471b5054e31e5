//! The simulated arm: the finger over a scene (`crackbot-sim`) with its sensor behind the real
//! firmware code, driven through the [`Arm`] interface like any arm.
//!
//! * [`world`]: the arm and the finger over a scene, stepped one sensor sample at a time.
//! * [`sensor`]: the simulated sensor streaming 400 Hz frames into a pseudo-terminal.
//! * [`SimArm`]: the world as an [`Arm`]; [`SimController`]: the world, its sensor and the link
//!   side in this process (what `crackbot-controller --arm sim` and the no-argument mission run).

pub mod follow;
pub mod sensor;
pub mod world;

use std::net::{SocketAddr, UdpSocket};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use crackbot_link::Security;
use crackbot_sim::Scene;

use crate::arm::{Arm, ArmState};
use crate::command::Checked;
use crate::limits::{Limits, Refusal};
use crate::server::{ControllerError, Faults, LinkServer, LinkSettings, ServerReport};
use crate::ControllerClock;
use sensor::{lock, SensorControl, Shared, SharedWorld, SimSensor};
use world::World;

/// The simulated world as an [`Arm`]: commands go to the world, its state is the last tick's.
#[derive(Debug, Clone)]
pub struct SimArm {
    shared: SharedWorld,
    clock: ControllerClock,
    control: Option<SensorControl>,
}

impl SimArm {
    /// The arm over a world shared with its sensor; `control` injects sensor stalls.
    pub fn new(
        shared: SharedWorld,
        clock: ControllerClock,
        control: Option<SensorControl>,
    ) -> Self {
        SimArm {
            shared,
            clock,
            control,
        }
    }
}

impl Arm for SimArm {
    fn limits(&self) -> Limits {
        *lock(&self.shared).world.limits()
    }

    fn now_us(&self) -> u64 {
        self.clock.at_tick(lock(&self.shared).world.tick_count())
    }

    fn apply(&mut self, command: Checked) -> Result<Option<u32>, Refusal> {
        lock(&self.shared).world.apply(command)
    }

    fn stop(&mut self) {
        lock(&self.shared).world.stop();
    }

    fn is_busy(&self) -> bool {
        lock(&self.shared).world.is_busy()
    }

    fn state(&self) -> Option<ArmState> {
        lock(&self.shared).last.map(|t| ArmState {
            time_us: self.clock.at_tick(t.tick),
            pose: t.pose,
            velocity: t.velocity,
            mode: t.mode,
            progress: t.progress,
        })
    }

    fn take_finished(&mut self) -> Vec<u32> {
        std::mem::take(&mut lock(&self.shared).finished)
    }

    fn fault(&self) -> Option<(u16, String)> {
        lock(&self.shared).fault.clone().map(|f| (1, f))
    }

    fn stall_sensor(&mut self, d: Duration) {
        if let Some(c) = &self.control {
            c.stall_for(d);
        }
    }
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

    /// The link side's share of the settings.
    pub fn link(&self) -> LinkSettings {
        LinkSettings {
            security: self.security.clone(),
            epoch_file: self.epoch_file.clone(),
            link_id: self.link_id,
            state_rate_hz: self.state_rate_hz,
            watchdog: self.watchdog,
            faults: self.faults.clone(),
        }
    }
}

/// The shared world of a scene, before any tick.
pub fn shared_world(scene: &Scene, seed: u64) -> Result<SharedWorld, ControllerError> {
    let world = World::new(scene, seed)?;
    Ok(Arc::new(Mutex::new(Shared {
        world,
        last: None,
        finished: Vec::new(),
        fault: None,
    })))
}

/// The simulated controller running in this process: its sensor thread and its link thread.
#[derive(Debug)]
pub struct SimController {
    sensor: Option<SimSensor>,
    server: Option<LinkServer>,
    shared: SharedWorld,
}

impl SimController {
    /// Starts the controller on `socket` (already bound: its address is the one the host talks
    /// to), talking to the host at `host`.
    pub fn spawn(
        config: &ServerConfig,
        socket: UdpSocket,
        host: SocketAddr,
    ) -> Result<SimController, ControllerError> {
        let link = config.link();
        let shared = shared_world(&config.scene, config.seed)?;
        let sensor = SimSensor::spawn(shared.clone(), config.clock.speedup)?;
        let arm = SimArm::new(shared.clone(), config.clock, Some(sensor.control()));
        let server = LinkServer::spawn(arm, link, socket, host)?;
        Ok(SimController {
            sensor: Some(sensor),
            server: Some(server),
            shared,
        })
    }

    /// The sensor's pseudo-terminal (open it as the robot's serial port).
    pub fn sensor_path(&self) -> &str {
        self.sensor.as_ref().map_or("", |s| s.path())
    }

    /// The controller's UDP address.
    pub fn addr(&self) -> SocketAddr {
        self.server
            .as_ref()
            .map_or_else(|| SocketAddr::from(([0, 0, 0, 0], 0)), LinkServer::addr)
    }

    /// The arm's true pose now (ground truth for tests), mm.
    pub fn true_pose(&self) -> [f64; 3] {
        lock(&self.shared).world.pose()
    }

    /// Stops the controller and its sensor and returns its report.
    pub fn shutdown(mut self) -> Result<ServerReport, ControllerError> {
        let report = match self.server.take() {
            Some(s) => s.shutdown(),
            None => Err(ControllerError::Panicked),
        };
        if let Some(s) = self.sensor.take() {
            s.stop()?;
        }
        report
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_links_longest_slide_is_the_simulators() {
        assert_eq!(
            crate::command::MAX_STROKE_MM,
            crackbot_sim::run::MAX_STROKE_MM
        );
    }
}
