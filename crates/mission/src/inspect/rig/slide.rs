//! A commanded slide: the finger down on the plate from one point to another at a speed,
//! recorded (the stroke's samples with the position along it interpolated from the arm's
//! states), retried once when the sensor stalled or the controller restarted.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use crackbot_link::{Contact, Message, Point2};

use super::arm::{down_at, mapped_states};
use super::context::Rig;
use super::feel::Feel;
use super::live::Stroke;
use super::recording::Recorded;
use crate::inspect::geometry::{along, unit};
use crate::inspect::progress::{Progress, StrokeSample};
use crate::MissionError;

impl Rig<'_> {
    /// Commands one pass and records it: the samples of the stroke (finger down, sliding) with
    /// the position along the pass (mm from `a`) interpolated from the arm's states. Retries once
    /// when the sensor stalled or the controller restarted.
    pub(crate) fn slide_and_record(
        &mut self,
        id: u32,
        (a, b): ([f64; 2], [f64; 2]),
        speed: f64,
        dir: u8,
        feel: &mut Feel<'_>,
    ) -> Result<(Recorded, u32), MissionError> {
        let mut attempts = 0;
        loop {
            attempts += 1;
            match self.try_slide(id, (a, b), speed, dir, feel) {
                Ok(r) => return Ok((r, attempts)),
                Err(
                    e @ (MissionError::SensorStalled { .. } | MissionError::ControllerRestarted),
                ) if attempts < 2 => {
                    tracing::warn!("slide {id}: {e}; sliding again");
                    self.arm.restarted = false;
                    self.wait_for_stream()?;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// One attempt of [`Self::slide_and_record`].
    fn try_slide(
        &mut self,
        id: u32,
        (a, b): ([f64; 2], [f64; 2]),
        speed: f64,
        dir: u8,
        feel: &mut Feel<'_>,
    ) -> Result<Recorded, MissionError> {
        let first_sample = self.sensor.samples.len();
        feel.begin(id, (a, b), dir, first_sample);
        self.stroke = Some(Stroke::new(Some(id), a, b));
        self.arm.errors.clear();
        // A retried slide keeps its id: forget the first attempt's end.
        self.arm.done.retain(|&d| d != id);
        let seq = self.arm.command(&Message::Slide(crackbot_link::Slide {
            id,
            start: Point2 {
                x_mm: a[0] as f32,
                y_mm: a[1] as f32,
            },
            end: Point2 {
                x_mm: b[0] as f32,
                y_mm: b[1] as f32,
            },
            speed_mm_s: speed as f32,
            contact: Contact::DepthMm(1.0),
            valid_until_us: self.arm.deadline_us()?,
        }))?;
        self.follow_slide(id, seq, (a, b), speed, feel)?;
        self.stroke_samples(id, (a, b), speed, first_sample)
    }

    /// Follows slide `id` (command `seq`, from `a` to `b` at `speed`) until the controller says
    /// it is done, showing what the finger feels; fails when it is refused, the controller
    /// restarts, the sensor stalls, the arm's state stream stops or it takes far too long.
    fn follow_slide(
        &mut self,
        id: u32,
        seq: u32,
        (a, b): ([f64; 2], [f64; 2]),
        speed: f64,
        feel: &mut Feel<'_>,
    ) -> Result<(), MissionError> {
        let config = self.config;
        let here = self.arm.here();
        let travel = (a[0] - here[0]).hypot(a[1] - here[1]) / config.site.arm.travel_speed_mm_s;
        let stroke = (b[0] - a[0]).hypot(b[1] - a[1]) / speed;
        let budget = Duration::from_secs_f64((travel + stroke) / config.speedup * 1.5 + 3.0);
        let deadline = Instant::now() + budget;
        let stall_limit = Duration::from_millis(500);
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return Err(MissionError::Interrupted);
            }
            self.pump(Duration::from_millis(2))?;
            let latest = self.arm.states.back().map(|s| &s.state);
            if let Some(f) = feel.update(&self.sensor.samples, latest)? {
                (self.progress)(&Progress::Feeling(f));
            }
            if let Some(e) = self.arm.errors.iter().find(|e| e.seq == seq) {
                return Err(MissionError::Refused {
                    what: format!("slide {id}"),
                    reason: e.text.to_string(),
                });
            }
            if self.arm.done.contains(&id) {
                break;
            }
            if self.arm.restarted {
                return Err(MissionError::ControllerRestarted);
            }
            if self.sensor.last_at.elapsed() > stall_limit {
                // Wait for the stream to come back before sliding again, or give up.
                self.wait_for_stream()?;
                self.arm.stop();
                return Err(MissionError::SensorStalled {
                    port: self.sensor.path.clone(),
                    detail: format!("no sample for {} ms", stall_limit.as_millis()),
                });
            }
            self.check_progress(deadline, budget, || format!("slide {id}"))?;
        }
        Ok(())
    }

    /// The samples of slide `id` from `a` to `b` at `speed` (those from `first_sample` on,
    /// taken while the arm was down in it) with their positions along it, shown to the front
    /// end; fails as a stall where the sensor fell silent inside the stroke.
    fn stroke_samples(
        &mut self,
        id: u32,
        (a, b): ([f64; 2], [f64; 2]),
        speed: f64,
        first_sample: usize,
    ) -> Result<Recorded, MissionError> {
        let config = self.config;
        // A few more states, so the end of the stroke is bracketed.
        let settle = Instant::now() + Duration::from_millis(40);
        while Instant::now() < settle {
            self.pump(Duration::from_millis(2))?;
        }
        // The stroke's samples: the arm down (z ≈ 0) in slide `id` by the states on both sides.
        let mut samples = Vec::new();
        let mut positions = Vec::new();
        let u = unit(a, b);
        let mapped = mapped_states(self.arm);
        // A silence of the sensor inside the stroke (a stall the stroke outlasted): slide again.
        let nominal_us: f64 = 2500.0 / config.speedup;
        let mut last_down: Option<f64> = None;
        let mut shown = Vec::new();
        for s in &self.sensor.samples[first_sample..] {
            let host = self.sensor.sync.to_host(s.device_us).unwrap_or(s.host_us);
            let Some(p) = down_at(&mapped, host, id) else {
                continue;
            };
            // (The floor keeps scheduling hiccups of a loaded host from reading as stalls.)
            if let Some(l) = last_down.filter(|l| host - l > (40.0 * nominal_us).max(200_000.0)) {
                return Err(MissionError::SensorStalled {
                    port: self.sensor.path.clone(),
                    detail: format!("no sample for {:.0} ms of the stroke", (host - l) / 1e3),
                });
            }
            last_down = Some(host);
            samples.push(s.raw.map(f64::from));
            positions.push(along(a, u, p));
            shown.push(StrokeSample {
                t_s: host / 1e6,
                raw: s.raw,
                along_mm: along(a, u, p),
            });
        }
        // Frames lost to a stall that lasted past the stroke's end: too few samples for the stroke.
        let expected =
            (b[0] - a[0]).hypot(b[1] - a[1]) / speed * f64::from(crackbot_protocol::SAMPLE_RATE_HZ);
        if (samples.len() as f64) < 0.8 * expected {
            return Err(MissionError::SensorStalled {
                port: self.sensor.path.clone(),
                detail: format!(
                    "{} samples of the stroke, {expected:.0} expected",
                    samples.len()
                ),
            });
        }
        (self.progress)(&Progress::Stroked {
            slide: id,
            samples: shown,
        });
        Ok((samples, positions))
    }
}
