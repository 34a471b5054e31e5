//! A raised pass: the finger held above the plate from where it is to a point, recorded, and
//! stopped by a guard when something stands under the line (the print check's passes).

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use crackbot_link::Message;

use super::arm::{mapped_states, pose, position_at};
use super::context::Rig;
use super::live::Stroke;
use super::recording::Recorded;
use crate::inspect::geometry::{along, unit};
use crate::MissionError;

/// Something standing under a raised pass: where the pass was stopped and how far the proximity
/// channel had risen above the sound surface's level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Obstruction {
    /// Mean P of the latest [`GUARD_MEAN_SAMPLES`] samples above the pass's first
    /// [`GUARD_REFERENCE_SAMPLES`] (their median), counts.
    pub(crate) rise_counts: f64,
    /// Where the arm was along the pass's line when the guard stopped it, mm from `line_start`.
    pub(crate) at_mm: f64,
}

/// Samples at the start of a guarded pass whose median is the sound surface's level.
pub(crate) const GUARD_REFERENCE_SAMPLES: usize = 20;
/// Samples averaged for the guard's reading.
pub(crate) const GUARD_MEAN_SAMPLES: usize = 4;

impl Rig<'_> {
    /// Moves the finger, held `z` mm above the plate, from where it is to `to` at `speed` and
    /// records the pass: the samples taken after the command while the arm was at that height
    /// (moving, or at rest at either end), with their
    /// position along the line from `line_start` towards `to` (mm). The print check's raised
    /// pass ([`crackbot_tactile::print_check`]).
    ///
    /// With `guard` (counts; for a pass that starts at height `z`), the pass is stopped (the arm
    /// lifts to its travel height) as soon as the proximity channel rises that far above the
    /// level it read at the start: something stands under the line, closer to the fibre than
    /// the plate (a screw head taller than `z` would be struck). The samples from where the rise
    /// began are dropped, and the obstruction is returned.
    pub(crate) fn hover_and_record(
        &mut self,
        line_start: [f64; 2],
        to: [f64; 2],
        z: f64,
        speed: f64,
        guard: Option<f64>,
    ) -> Result<(Recorded, Option<Obstruction>), MissionError> {
        let first_sample = self.sensor.samples.len();
        self.stroke = Some(Stroke::new(None, line_start, to));
        self.arm.errors.clear();
        let seq = self.arm.command(&Message::MoveTo(crackbot_link::MoveTo {
            pose: crackbot_link::Pose {
                x_mm: to[0] as f32,
                y_mm: to[1] as f32,
                z_mm: z as f32,
            },
            speed_mm_s: speed as f32,
            valid_until_us: self.arm.deadline_us()?,
        }))?;
        let guarded = guard.map(|g| (g, first_sample));
        let (reference, obstruction) =
            self.follow_hover(seq, (line_start, to), z, speed, guarded)?;
        self.stroke = None;
        self.await_lagging_samples()?;
        let (mut samples, mut positions) = self.level_samples(first_sample, (line_start, to), z);
        // A stopped pass keeps what it read before the rise began (a quarter of the guard).
        if let (Some(g), Some(r), Some(_)) = (guard, reference, obstruction) {
            let rise = samples.iter().position(|s| s[3] - r > g / 4.0);
            if let Some(i) = rise {
                samples.truncate(i);
                positions.truncate(i);
            }
        }
        Ok(((samples, positions), obstruction))
    }

    /// Follows the move `seq` towards `to` at height `z` and `speed` until the arm arrives,
    /// stopping it where the guard `(counts, first sample)` sees something rise under the line
    /// (from `line_start`): the guard's reference level and the obstruction, if any.
    fn follow_hover(
        &mut self,
        seq: u32,
        (line_start, to): ([f64; 2], [f64; 2]),
        z: f64,
        speed: f64,
        guard: Option<(f64, usize)>,
    ) -> Result<(Option<f64>, Option<Obstruction>), MissionError> {
        let mut reference: Option<f64> = None;
        let here = self.arm.here();
        let dist = (to[0] - here[0]).hypot(to[1] - here[1]);
        let budget = Duration::from_secs_f64(dist / speed / self.config.speedup * 1.5 + 3.0);
        let deadline = Instant::now() + budget;
        let arrived =
            |p: [f64; 3]| (p[0] - to[0]).hypot(p[1] - to[1]) < 0.05 && (p[2] - z).abs() < 0.05;
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return Err(MissionError::Interrupted);
            }
            self.pump(Duration::from_millis(2))?;
            if let Some((g, first_sample)) = guard {
                let p = &self.sensor.samples[first_sample..];
                if reference.is_none() && p.len() >= GUARD_REFERENCE_SAMPLES {
                    reference = Some(guard_reference(p));
                }
                if let Some(r) = reference {
                    let latest = &p[p.len() - GUARD_MEAN_SAMPLES..];
                    let mean = latest.iter().map(|s| f64::from(s.raw[3])).sum::<f64>()
                        / GUARD_MEAN_SAMPLES as f64;
                    if mean - r > g {
                        self.arm.stop();
                        let here = self.arm.here();
                        let obstruction = Obstruction {
                            rise_counts: mean - r,
                            at_mm: along(line_start, unit(line_start, to), here),
                        };
                        return Ok((reference, Some(obstruction)));
                    }
                }
            }
            if let Some(e) = self.arm.errors.iter().find(|e| e.seq == seq) {
                return Err(MissionError::Refused {
                    what: format!("the pass held {z} mm above the plate"),
                    reason: e.text.to_string(),
                });
            }
            if let Some(s) = self.arm.states.back() {
                if s.state.mode == crackbot_link::Mode::Idle && arrived(pose(&s.state)) {
                    break;
                }
            }
            if self.arm.restarted {
                return Err(MissionError::ControllerRestarted);
            }
            self.check_progress(deadline, budget, || {
                format!("the pass held {z} mm above the plate")
            })?;
        }
        Ok((reference, None))
    }

    /// The sensor's samples lag the arm's states: waits (100 ms at most) until one taken after
    /// the arm arrived (or was stopped) has come in.
    fn await_lagging_samples(&mut self) -> Result<(), MissionError> {
        let arrived_us = mapped_states(self.arm).last().map(|(h, _)| *h);
        let wait_until = Instant::now() + Duration::from_millis(100);
        while let Some(t) = arrived_us {
            let latest = self
                .sensor
                .samples
                .last()
                .map(|s| self.sensor.sync.to_host(s.device_us).unwrap_or(s.host_us));
            if latest.is_some_and(|l| l >= t) || Instant::now() > wait_until {
                break;
            }
            self.pump(Duration::from_millis(2))?;
        }
        Ok(())
    }

    /// The samples from `first_sample` on taken while the arm was held at height `z` (moving,
    /// or at rest at either end), with their positions along the line from `line_start`
    /// towards `to`, mm.
    fn level_samples(
        &mut self,
        first_sample: usize,
        (line_start, to): ([f64; 2], [f64; 2]),
        z: f64,
    ) -> Recorded {
        let u = unit(line_start, to);
        let mapped = mapped_states(self.arm);
        let (mut samples, mut positions) = (Vec::new(), Vec::new());
        for s in &self.sensor.samples[first_sample..] {
            let host = self.sensor.sync.to_host(s.device_us).unwrap_or(s.host_us);
            let Some((p, mode)) = position_at(&mapped, host) else {
                continue;
            };
            // Moving, or still at rest at the start or already at the end (at a simulation
            // speed-up the states come far apart and the mode flips between them).
            let level = matches!(
                mode,
                crackbot_link::Mode::Moving | crackbot_link::Mode::Idle
            );
            if level && (p[2] - z).abs() < 0.05 {
                samples.push(s.raw.map(f64::from));
                positions.push(along(line_start, u, p));
            }
        }
        (samples, positions)
    }
}

/// The sound surface's level at a guarded pass's start: the median proximity of its first
/// [`GUARD_REFERENCE_SAMPLES`] samples (`samples` holds at least as many), counts.
fn guard_reference(samples: &[super::sensor::TimedSample]) -> f64 {
    let mut first: Vec<f64> = samples[..GUARD_REFERENCE_SAMPLES]
        .iter()
        .map(|s| f64::from(s.raw[3]))
        .collect();
    first.sort_by(f64::total_cmp);
    first[GUARD_REFERENCE_SAMPLES / 2]
}
