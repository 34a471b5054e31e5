//! The rig's and the output's sections of a mission's configuration: what the mission runs on
//! (hardware, or the simulated scene), the place ([`Site`]), the simulation's speed and seed,
//! injected faults, and where the report, the recordings and the log go.

use std::net::SocketAddr;
use std::path::PathBuf;

#[cfg(feature = "sim")]
use crackbot_controller::{ControllerClock, Faults};
#[cfg(feature = "sim")]
use crackbot_sim::Scene;
use serde::{Deserialize, Serialize};

use super::site::Site;
use crate::MissionError;

/// Real hardware in place of the simulated parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hardware {
    /// The sensor's serial device (or a pseudo-terminal).
    pub serial: String,
    /// The manipulator controller's UDP address.
    pub controller: SocketAddr,
    /// This host's UDP address for the link (the controller sends to it).
    #[serde(default = "default_bind")]
    pub bind: SocketAddr,
    /// The link's pre-shared key file (mode 0600).
    pub key_file: PathBuf,
    /// The camera: a V4L2 device, a video file or stream URL, or an image file
    /// ([`crackbot_vision::camera::CameraSource::parse`]).
    #[serde(default)]
    pub camera: Option<PathBuf>,
    /// The camera's pixel → surface calibration (`crackbot homography fit`); or, in its place,
    /// [`RigConfig::camera_calibration`].
    #[serde(default)]
    pub homography: Option<PathBuf>,
    /// How frames are asked of the camera: mode, exposure, gain, frames dropped first.
    #[serde(default)]
    pub capture: crackbot_vision::camera::CaptureOptions,
}

/// This host's link address when none is given (`--bind`'s default).
pub const DEFAULT_BIND: &str = "0.0.0.0:7701";

/// [`DEFAULT_BIND`] as an address.
fn default_bind() -> SocketAddr {
    SocketAddr::from(([0, 0, 0, 0], 7701))
}

/// What the mission runs on: `[rig]` of the configuration file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigConfig {
    /// Real hardware; `None`: the simulated controller and sensor over the scene (feature
    /// `sim`).
    #[serde(default)]
    pub hardware: Option<Hardware>,
    /// What the mission knows of the place: the arm's box and speeds, the finger's fibre.
    pub site: Site,
    /// Simulation speed-up (1: real time).
    pub speedup: f64,
    /// Seed of the simulated sensor and camera.
    pub seed: u64,
    /// The camera's lens and the plate's pose (`crackbot calibrate camera` then `surface`): the
    /// frame is undistorted and mapped to the plate through it, in place of the hardware's
    /// homography or the simulated scene's exact one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_calibration: Option<PathBuf>,
    /// The simulated scene ([`RigConfig::set_scene`]); given by `--scene`, not by the file.
    #[cfg(feature = "sim")]
    #[serde(skip)]
    scene: Option<Scene>,
    /// The simulated controller's clock (offset, drift injected).
    #[cfg(feature = "sim")]
    #[serde(skip)]
    pub clock: ControllerClock,
    /// Faults injected into the simulated controller.
    #[cfg(feature = "sim")]
    #[serde(skip)]
    pub faults: Faults,
    /// Link packet faults injected on the host's side.
    #[serde(skip)]
    pub host_link_faults: Option<crackbot_link::FaultConfig>,
}

impl RigConfig {
    /// The rig at `site`: simulated at real time (seed 7) until [`hardware`](Self::hardware) or a
    /// scene is set.
    pub fn at(site: Site) -> Self {
        RigConfig {
            hardware: None,
            site,
            speedup: 1.0,
            seed: 7,
            camera_calibration: None,
            #[cfg(feature = "sim")]
            scene: None,
            #[cfg(feature = "sim")]
            clock: ControllerClock::default(),
            #[cfg(feature = "sim")]
            faults: Faults::default(),
            host_link_faults: None,
        }
    }

    /// Refuses a rig setting out of range: the site's, the speed-up.
    pub fn check(&self) -> Result<(), MissionError> {
        self.site.clone().checked()?;
        if !(self.speedup.is_finite() && self.speedup > 0.0 && self.speedup <= 1000.0) {
            return Err(MissionError::Setting {
                field: "rig.speedup",
                value: self.speedup,
                allowed: "(0, 1000]",
            });
        }
        Ok(())
    }

    /// The fields the file does not hold (the scene, injected faults) taken from `other`.
    pub(crate) fn keep_unfiled(&mut self, other: &RigConfig) {
        #[cfg(feature = "sim")]
        {
            self.scene.clone_from(&other.scene);
            self.clock = other.clock;
            self.faults = other.faults.clone();
        }
        self.host_link_faults.clone_from(&other.host_link_faults);
    }
}

#[cfg(feature = "sim")]
impl RigConfig {
    /// The simulated scene, if one was given.
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_ref()
    }

    /// Simulates `scene`, and takes its site (name, manipulator, fibre) for the mission's.
    pub fn set_scene(&mut self, scene: Scene) {
        self.site = Site::of_scene(&scene);
        self.scene = Some(scene);
    }
}

/// Where the mission's report, recordings and log go: `[output]` of the configuration file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Where the report and every recording go.
    pub out_dir: PathBuf,
    /// Write the mission's log, `mission.mcap` in [`out_dir`](Self::out_dir) (on by default):
    /// every channel a front end sees, stamped with the host's clock (`crackbot-mcap`).
    pub mcap: bool,
    /// Serve the log's channels live over the Foxglove WebSocket protocol on this address
    /// (port 0: any free one; the feature `foxglove`). `None`: no live server.
    #[cfg(feature = "foxglove")]
    #[serde(default)]
    pub foxglove: Option<SocketAddr>,
    /// Publish the log's messages live on ROS 2 topics over DDS on this domain (the feature
    /// `ros2`; `crates/rosbag/docs/ros2.md`). `None`: none. Needs the log ([`mcap`](Self::mcap)).
    #[cfg(feature = "ros2")]
    #[serde(default)]
    pub ros2_domain: Option<u16>,
}

impl OutputConfig {
    /// Everything into `out_dir`, with the log and no live server.
    pub fn new(out_dir: impl Into<PathBuf>) -> Self {
        OutputConfig {
            out_dir: out_dir.into(),
            mcap: true,
            #[cfg(feature = "foxglove")]
            foxglove: None,
            #[cfg(feature = "ros2")]
            ros2_domain: None,
        }
    }
}
