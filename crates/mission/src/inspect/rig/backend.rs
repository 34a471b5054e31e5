//! What a mission runs on: a [`RigBackend`] says where the arm's controller and the sensor are,
//! starts what must be started, and gives the camera's frame. The mission's own arm and sensor
//! code (`arm.rs`, `sensor.rs`) is the same on every rig: it always talks to the
//! controller over the authenticated UDP link and reads the sensor over a serial port, so what
//! differs is only what answers at the other end.
//!
//! * [`HardwareRig`]: a real controller, serial port and camera ([`Hardware`]).
//! * `SimulatedRig` (cargo feature `sim`, `simulated.rs`): the simulated controller and emulated sensor
//!   started in-process over loopback UDP and a pseudo-terminal, and the scene rendered as the
//!   camera's frame.

use std::net::{SocketAddr, UdpSocket};
use std::path::Path;

use crackbot_imaging::Homography;
use crackbot_link::Key;
use image::RgbImage;

use super::settings::{Hardware, RigConfig};
use crate::error::link_err;
use crate::inspect::report::InspectMode;
use crate::MissionError;

/// Where a mission's arm and sensor are, once started.
pub struct Connection {
    /// This host's UDP socket for the link.
    pub socket: UdpSocket,
    /// The controller's UDP address.
    pub controller: SocketAddr,
    /// The link's pre-shared key.
    pub key: Key,
    /// The sensor's serial device (or pseudo-terminal).
    pub sensor_port: String,
}

/// A mission's rig: the arm's controller, the sensor and the camera.
pub trait RigBackend {
    /// Starts what the rig needs (its state files under `state_dir`) and says where the arm and
    /// the sensor are (`mode` named in errors).
    fn connect(
        &mut self,
        config: &RigConfig,
        mode: InspectMode,
        state_dir: &Path,
    ) -> Result<Connection, MissionError>;

    /// One camera frame and its pixel → surface homography (fused and vision missions, `mode`
    /// named in errors).
    fn frame(
        &mut self,
        config: &RigConfig,
        mode: InspectMode,
    ) -> Result<(RgbImage, Homography), MissionError>;

    /// One camera frame alone, for a mission that maps it through a camera calibration file
    /// (`rig.camera_calibration`) instead of the rig's homography.
    fn image(&mut self, config: &RigConfig, mode: InspectMode) -> Result<RgbImage, MissionError>;

    /// Stops what [`connect`](Self::connect) started (nothing on hardware). Called once, after
    /// the arm was stopped.
    fn shutdown(&mut self) {}
}

/// Real hardware: the controller at [`Hardware::controller`], the sensor on
/// [`Hardware::serial`], frames from [`Hardware::camera`].
pub struct HardwareRig {
    hardware: Hardware,
}

impl HardwareRig {
    /// The rig of `hardware`.
    pub fn new(hardware: Hardware) -> Self {
        HardwareRig { hardware }
    }
}

impl RigBackend for HardwareRig {
    fn connect(
        &mut self,
        _: &RigConfig,
        _: InspectMode,
        _: &Path,
    ) -> Result<Connection, MissionError> {
        let hw = &self.hardware;
        let key = Key::from_file(&hw.key_file).map_err(|e| link_err("the link key", e))?;
        Ok(Connection {
            socket: bind(hw.bind)?,
            controller: hw.controller,
            key,
            sensor_port: hw.serial.clone(),
        })
    }

    fn frame(
        &mut self,
        config: &RigConfig,
        mode: InspectMode,
    ) -> Result<(RgbImage, Homography), MissionError> {
        let cal = self
            .hardware
            .homography
            .clone()
            .ok_or(MissionError::Missing {
                mode: mode.as_str(),
                what: "the camera's pixel → surface calibration (--camera-calibration FILE from \
                   `crackbot calibrate camera` and `surface`, or --homography FILE from \
                   `crackbot homography fit`)",
            })?;
        let image = self.image(config, mode)?;
        let h = crackbot_vision::homography::HomographyCalibration::load(&cal)?.homography()?;
        Ok((image, h))
    }

    fn image(&mut self, _: &RigConfig, mode: InspectMode) -> Result<RgbImage, MissionError> {
        use crackbot_vision::camera::{grab, CameraSource, DEFAULT_TIMEOUT};
        let hw = &self.hardware;
        let camera = hw.camera.as_ref().ok_or(MissionError::Missing {
            mode: mode.as_str(),
            what: "a camera (--camera DEVICE|FILE|URL)",
        })?;
        let source = CameraSource::parse(&camera.to_string_lossy());
        Ok(grab(&source, None, &hw.capture, DEFAULT_TIMEOUT)?)
    }
}

/// A UDP socket bound to `a`.
pub(crate) fn bind(a: SocketAddr) -> Result<UdpSocket, MissionError> {
    UdpSocket::bind(a).map_err(|e| link_err(format!("binding {a}"), e))
}
