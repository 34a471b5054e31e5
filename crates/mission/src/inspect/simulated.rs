//! The simulated rig (cargo feature `sim`): the simulated controller and emulated sensor over
//! loopback UDP and a pseudo-terminal, and the scene rendered as the camera's frame.

use std::net::SocketAddr;
use std::path::Path;

use crackbot_controller::{ControllerClock, ServerConfig, SimController};
use crackbot_imaging::Homography;
use crackbot_link::{Key, Security};
use image::RgbImage;

use super::config::InspectConfig;
use super::rig::{bind, Connection, RigBackend};
use crate::MissionError;

/// The simulated controller of [`InspectConfig::scene`], started by
/// [`connect`](RigBackend::connect) with a fresh random key per mission that is never written
/// anywhere (both ends live in this process).
#[derive(Default)]
pub struct SimulatedRig {
    controller: Option<SimController>,
}

impl RigBackend for SimulatedRig {
    fn connect(
        &mut self,
        config: &InspectConfig,
        state_dir: &Path,
    ) -> Result<Connection, MissionError> {
        let link = |e: std::io::Error| MissionError::Link(e.to_string());
        let loopback: SocketAddr = ([127, 0, 0, 1], 0).into();
        let socket = bind(loopback)?;
        let ctrl_socket = bind(loopback)?;
        let host_addr = socket.local_addr().map_err(link)?;
        let controller: SocketAddr = ctrl_socket.local_addr().map_err(link)?;
        let key_bytes: [u8; 32] = rand::random();
        let key = Key::from_bytes(&key_bytes).map_err(|e| MissionError::Link(e.to_string()))?;
        let mut server = ServerConfig::new(
            scene_of(config)?.clone(),
            Security::Signed(key.clone()),
            state_dir.join("controller.epoch"),
        );
        server.seed = config.seed;
        server.clock = ControllerClock {
            speedup: config.speedup,
            ..config.clock
        };
        server.faults = config.faults.clone();
        let sim = SimController::spawn(server, ctrl_socket, host_addr)?;
        let sensor_port = sim.sensor_path().to_string();
        self.controller = Some(sim);
        Ok(Connection {
            socket,
            controller,
            key,
            sensor_port,
        })
    }

    fn frame(&mut self, config: &InspectConfig) -> Result<(RgbImage, Homography), MissionError> {
        use crackbot_sim::render::{render, CrackAssets, RenderOptions};
        let assets = CrackAssets::load_default()?;
        let frame = render(
            scene_of(config)?,
            &assets,
            &RenderOptions::default(),
            config.seed,
        )?;
        let h = Homography::from_nalgebra(
            frame
                .plate_to_image
                .try_inverse()
                .ok_or(MissionError::SingularHomography)?,
        )
        .map_err(|_| MissionError::SingularHomography)?;
        Ok((frame.image, h))
    }

    fn shutdown(&mut self) {
        if let Some(c) = self.controller.take() {
            let _ = c.shutdown();
        }
    }
}

/// The scene `config` simulates, or an error saying it has none.
fn scene_of(config: &InspectConfig) -> Result<&crackbot_sim::Scene, MissionError> {
    config.scene().ok_or(MissionError::Missing {
        mode: config.mode.as_str(),
        what: "a scene to simulate (InspectConfig::new or set_scene), or hardware",
    })
}
