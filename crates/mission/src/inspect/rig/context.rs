//! The rig as a step sees it ([`Rig`]): the arm, the sensor, the camera's backend, the stop
//! flag and the front end, with the stream pump that keeps the link alive and shows the
//! front end what arrived.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use super::arm::Arm;
use super::backend::RigBackend;
use super::live::{live_samples, new_poses, Stroke};
use super::sensor::Sensor;
use super::settings::RigConfig;
use crate::inspect::progress::{Progress, StreamHealth};
use crate::MissionError;

/// What a slide needs: the mission's settings, the arm, the sensor, the rig's camera, the stop
/// flag and the front end's progress callback, which also sees every sensor sample as it
/// arrives.
pub(crate) struct Rig<'a> {
    pub(crate) config: &'a RigConfig,
    /// Where the mission's recordings go.
    pub(crate) out_dir: &'a Path,
    pub(crate) arm: &'a mut Arm,
    pub(crate) sensor: &'a mut Sensor,
    pub(crate) backend: &'a mut dyn RigBackend,
    pub(crate) stop: &'a AtomicBool,
    pub(crate) progress: &'a mut dyn FnMut(&Progress),
    /// The line the finger is moving along, for what is shown.
    pub(crate) stroke: Option<Stroke>,
    /// Samples already shown to the front end.
    shown: usize,
    /// The controller time of the last arm state shown.
    pose_shown_us: Option<u64>,
    /// The times of the last pose and sample shown, s (neither stream goes back).
    shown_t_s: (f64, f64),
    last_shown: Instant,
    /// Samples and time at the last health event.
    health_at: (usize, Instant),
}

/// How often the front end is shown the samples that arrived.
const SHOW_SAMPLES_EVERY: Duration = Duration::from_millis(25);
/// How often it is shown the stream's health.
const SHOW_HEALTH_EVERY: Duration = Duration::from_millis(500);

impl<'a> Rig<'a> {
    pub(crate) fn new(
        (config, out_dir): (&'a RigConfig, &'a Path),
        arm: &'a mut Arm,
        sensor: &'a mut Sensor,
        backend: &'a mut dyn RigBackend,
        stop: &'a AtomicBool,
        progress: &'a mut dyn FnMut(&Progress),
    ) -> Self {
        Rig {
            config,
            out_dir,
            arm,
            sensor,
            backend,
            stop,
            progress,
            stroke: None,
            shown: 0,
            pose_shown_us: None,
            shown_t_s: (f64::NEG_INFINITY, f64::NEG_INFINITY),
            last_shown: Instant::now(),
            health_at: (0, Instant::now()),
        }
    }

    /// Takes what the arm and the sensor sent (waiting up to `wait` for the arm), and shows the
    /// front end the new samples every [`SHOW_SAMPLES_EVERY`]. Returns the samples taken.
    pub(crate) fn pump(&mut self, wait: Duration) -> Result<usize, MissionError> {
        self.arm.pump(wait)?;
        let n = self.sensor.drain()?;
        if self.sensor.samples.len() > self.shown && self.last_shown.elapsed() >= SHOW_SAMPLES_EVERY
        {
            let stroke = self.stroke;
            let stroke = stroke.as_ref();
            let poses = new_poses(self.arm, self.pose_shown_us, stroke, &mut self.shown_t_s.0);
            if let Some(last) = poses.last() {
                self.pose_shown_us = Some(last.controller_us);
                (self.progress)(&Progress::Poses { poses });
            }
            let samples = live_samples(
                self.arm,
                self.sensor,
                self.shown,
                stroke,
                &mut self.shown_t_s.1,
            );
            (self.progress)(&Progress::Samples { samples });
            self.shown = self.sensor.samples.len();
            self.last_shown = Instant::now();
        }
        let (n0, t0) = self.health_at;
        if t0.elapsed() >= SHOW_HEALTH_EVERY {
            let now = self.sensor.samples.len();
            let sensor = self.sensor.stream.stats();
            let link = self.arm.ep.stats();
            (self.progress)(&Progress::Health(StreamHealth {
                sample_rate_hz: (now - n0) as f64 / t0.elapsed().as_secs_f64(),
                frames: sensor.decoder.frames,
                crc_errors: sensor.decoder.crc_errors,
                gaps: sensor.gaps,
                missing_frames: sensor.missing_frames,
                link_sent: link.sent,
                link_retries: link.retries,
                link_rejected: link.rejected(),
                state_age_ms: self
                    .arm
                    .last_state_at
                    .map(|t| t.elapsed().as_secs_f64() * 1e3),
            }));
            self.health_at = (now, Instant::now());
        }
        Ok(n)
    }

    /// Waits (5 s at most, keeping the link alive) until the sensor streams again: samples that
    /// arrive now, not ones left in the queue. Stops the arm and fails when it stays silent.
    pub(crate) fn wait_for_stream(&mut self) -> Result<(), MissionError> {
        let resume = Instant::now() + Duration::from_secs(5);
        loop {
            let before = self.sensor.last_at;
            if self.pump(Duration::from_millis(5))? > 0
                && before.elapsed() < Duration::from_millis(50)
            {
                return Ok(());
            }
            if Instant::now() > resume {
                self.arm.stop();
                return Err(MissionError::NoSamples {
                    port: self.sensor.path.clone(),
                });
            }
        }
    }

    /// Stops the arm and fails when its state stream has been silent for 2 s (the controller is
    /// unreachable) or the command `what` outlasted its `budget` (ending at `deadline`).
    pub(crate) fn check_progress(
        &mut self,
        deadline: Instant,
        budget: Duration,
        what: impl FnOnce() -> String,
    ) -> Result<(), MissionError> {
        if self
            .arm
            .last_state_at
            .is_some_and(|t| t.elapsed() > Duration::from_secs(2))
        {
            self.arm.stop();
            return Err(MissionError::ControllerUnreachable {
                addr: self.arm.ep.peer_addr().to_string(),
            });
        }
        if Instant::now() > deadline {
            self.arm.stop();
            return Err(MissionError::Timeout {
                what: what(),
                seconds: budget.as_secs_f64(),
            });
        }
        Ok(())
    }
}
