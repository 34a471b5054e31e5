//! The simulated rig (cargo feature `sim`): the simulated controller and emulated sensor over
//! loopback UDP and a pseudo-terminal, and the scene rendered as the camera's frame.

use std::net::SocketAddr;
use std::path::Path;

use crackbot_controller::{ControllerClock, ServerConfig, SimController};
use crackbot_imaging::Homography;
use crackbot_link::{Key, Security};
use image::RgbImage;

use super::backend::{bind, Connection, RigBackend};
use super::settings::RigConfig;
use crate::error::link_err;
use crate::inspect::report::InspectMode;
use crate::MissionError;

/// The simulated controller of [`RigConfig::scene`], started by
/// [`connect`](RigBackend::connect) with a fresh random key per mission that is never written
/// anywhere (both ends live in this process).
#[derive(Default)]
pub struct SimulatedRig {
    controller: Option<SimController>,
}

impl RigBackend for SimulatedRig {
    fn connect(
        &mut self,
        config: &RigConfig,
        mode: InspectMode,
        state_dir: &Path,
    ) -> Result<Connection, MissionError> {
        let link = |e: std::io::Error| link_err("the simulated rig's sockets", e);
        let loopback: SocketAddr = ([127, 0, 0, 1], 0).into();
        let socket = bind(loopback)?;
        let ctrl_socket = bind(loopback)?;
        let host_addr = socket.local_addr().map_err(link)?;
        let controller: SocketAddr = ctrl_socket.local_addr().map_err(link)?;
        let key_bytes: [u8; 32] = rand::random();
        let key = Key::from_bytes(&key_bytes).map_err(|source| MissionError::LinkKey { source })?;
        let mut server = ServerConfig::new(
            scene_of(config, mode)?.clone(),
            Security::Signed(key.clone()),
            state_dir.join("controller.epoch"),
        );
        server.seed = config.seed;
        server.clock = ControllerClock {
            speedup: config.speedup,
            ..config.clock
        };
        server.faults = config.faults.clone();
        let sim = SimController::spawn(&server, ctrl_socket, host_addr)?;
        let sensor_port = sim.sensor_path().to_string();
        self.controller = Some(sim);
        Ok(Connection {
            socket,
            controller,
            key,
            sensor_port,
        })
    }

    fn frame(
        &mut self,
        config: &RigConfig,
        mode: InspectMode,
    ) -> Result<(RgbImage, Homography), MissionError> {
        let frame = render_scene(config, mode)?;
        let h = Homography::from_nalgebra(
            frame
                .plate_to_image
                .try_inverse()
                .ok_or(MissionError::SingularHomography)?,
        )
        .map_err(|_| MissionError::SingularHomography)?;
        Ok((frame.image, h))
    }

    fn image(&mut self, config: &RigConfig, mode: InspectMode) -> Result<RgbImage, MissionError> {
        Ok(render_scene(config, mode)?.image)
    }

    fn shutdown(&mut self) {
        if let Some(c) = self.controller.take() {
            let _ = c.shutdown();
        }
    }
}

/// The camera's frame of the scene `config` simulates (its lens included).
fn render_scene(
    config: &RigConfig,
    mode: InspectMode,
) -> Result<crackbot_sim::render::Frame, MissionError> {
    use crackbot_sim::render::{render, CrackAssets, RenderOptions};
    let assets = CrackAssets::load_default()?;
    Ok(render(
        scene_of(config, mode)?,
        &assets,
        &RenderOptions::default(),
        config.seed,
    )?)
}

/// The scene `config` simulates, or an error saying it has none (naming `mode`).
fn scene_of(config: &RigConfig, mode: InspectMode) -> Result<&crackbot_sim::Scene, MissionError> {
    config.scene().ok_or(MissionError::Missing {
        mode: mode.as_str(),
        what: "a scene to simulate (InspectConfig::new or set_scene), or hardware",
    })
}
