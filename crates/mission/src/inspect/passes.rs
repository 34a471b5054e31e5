//! One slide pass: command it, record it, cut it into classification units, classify it.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use crackbot_link::{Contact, Message, Point2};
use crackbot_planner::{Candidate, Workspace};
use crackbot_tactile::online::{OnlineClassifier, SlideVerdict};
use crackbot_tactile::print_check;

use super::arm::{down_at, mapped_states, pose, position_at, Arm};
use super::config::InspectConfig;
use super::feel::Feel;
use super::live::{live_samples, new_poses, Stroke};
use super::perceive::io_err;
use super::report::{CrackDoubt, Progress, StreamHealth, StrokeSample};
use super::rig::RigBackend;
use super::sensor::Sensor;
use crate::MissionError;

/// A candidate stroke's dip wider than the candidate (its detected width, or the planner's
/// assumed one) by more than this, mm, is looked at for several dips
/// ([`SEPARATE_DIPS_GAP_MM`]): the stroke also crossed a second crack or a print beside the
/// candidate, and the localiser, which counts everything between a dip's first and last sample
/// below half depth (a wide crack's middle can come back up), put the candidate between them. On
/// the simulated trial scenes 9540–9659 (real time), two such strokes (9566, 9570) put their
/// crack's report between two cracks 4.3–4.9 mm apart, 1.5 and 1.0 mm off its crack (9570: a
/// false report and a missed crack). Where the channel does not come back to the surface
/// between the dips (9325), or the detection spans both (9396), nothing changes.
pub const SEPARATE_DIPS_EXCESS_MM: f64 = 2.0;
/// Dips are separate where the smoothed proximity channel comes back within this share of the
/// dip's depth of the sound surface's level …
pub const SEPARATE_DIPS_BACK_SHARE: f64 = 0.15;
/// … for at least this much of the stroke's travel, mm. The dip nearest the candidate's axis is
/// then localised alone.
pub const SEPARATE_DIPS_GAP_MM: f64 = 0.5;

/// Where a pass crossed a crack, mm on the plate, and the crack's extent along the pass.
pub(super) type Crossing = ([f64; 2], Option<[[f64; 2]; 2]>);

/// A pass's samples (D1, D2, D3, P counts) and positions (mm along the pass).
pub(super) type Recorded = (Vec<[f64; 4]>, Vec<f64>);

/// Consecutive pieces of a pass, each covering `stroke_mm` of travel (tactile rows); a remainder
/// shorter than half a stroke joins the last piece.
pub(super) fn split_by_travel(positions: &[f64], stroke_mm: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &x) in positions.iter().enumerate() {
        if (x - positions[start]).abs() >= stroke_mm {
            out.push((start, i));
            start = i;
        }
    }
    if positions.len() > start {
        let short = positions
            .last()
            .is_some_and(|&x| (x - positions[start]).abs() < stroke_mm / 2.0);
        match out.last_mut() {
            // A short remainder joins the piece before it.
            Some(last) if short => last.1 = positions.len(),
            _ => out.push((start, positions.len())),
        }
    }
    out
}

/// The unit vector from `a` towards `b` (mm on the plate).
pub(super) fn unit(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l = d[0].hypot(d[1]).max(1e-9);
    [d[0] / l, d[1] / l]
}

/// How far the arm's pose `p` is along the line from `a` with unit direction `u`, mm.
pub(super) fn along(a: [f64; 2], u: [f64; 2], p: [f64; 3]) -> f64 {
    (p[0] - a[0]) * u[0] + (p[1] - a[1]) * u[1]
}

/// Both models over one pass: the recognition verdict and the width verdict.
pub(super) fn classify(
    online: &mut OnlineClassifier<'_>,
    online_width: &mut OnlineClassifier<'_>,
    samples: &[[f64; 4]],
    positions: &[f64],
    dirs: &[u8],
    fresh: bool,
) -> Result<(Option<SlideVerdict>, Option<SlideVerdict>), MissionError> {
    if fresh {
        online.reset();
        online_width.reset();
    }
    online.begin_slide();
    online_width.begin_slide();
    for ((s, x), d) in samples.iter().zip(positions).zip(dirs) {
        online.push(*s, *d, *x)?;
        online_width.push(*s, *d, *x)?;
    }
    Ok((online.end_slide()?, online_width.end_slide()?))
}

/// What a slide needs: the mission's settings, the arm, the sensor, the rig's camera, the stop
/// flag and the front end's progress callback, which also sees every sensor sample as it
/// arrives.
pub(super) struct Rig<'a> {
    pub(super) config: &'a InspectConfig,
    pub(super) arm: &'a mut Arm,
    pub(super) sensor: &'a mut Sensor,
    pub(super) backend: &'a mut dyn RigBackend,
    pub(super) stop: &'a AtomicBool,
    pub(super) progress: &'a mut dyn FnMut(&Progress),
    /// The line the finger is moving along, for what is shown.
    pub(super) stroke: Option<Stroke>,
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
    pub(super) fn new(
        config: &'a InspectConfig,
        arm: &'a mut Arm,
        sensor: &'a mut Sensor,
        backend: &'a mut dyn RigBackend,
        stop: &'a AtomicBool,
        progress: &'a mut dyn FnMut(&Progress),
    ) -> Self {
        Rig {
            config,
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
    pub(super) fn pump(&mut self, wait: Duration) -> Result<usize, MissionError> {
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

    /// Commands one pass and records it: the samples of the stroke (finger down, sliding) with
    /// the position along the pass (mm from `a`) interpolated from the arm's states. Retries once
    /// when the sensor stalled or the controller restarted.
    pub(super) fn slide_and_record(
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
                    continue;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// Waits (5 s at most, keeping the link alive) until the sensor streams again: samples that
    /// arrive now, not ones left in the queue. Stops the arm and fails when it stays silent.
    fn wait_for_stream(&mut self) -> Result<(), MissionError> {
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
    fn check_progress(
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

    /// One attempt of [`Self::slide_and_record`].
    fn try_slide(
        &mut self,
        id: u32,
        (a, b): ([f64; 2], [f64; 2]),
        speed: f64,
        dir: u8,
        feel: &mut Feel<'_>,
    ) -> Result<Recorded, MissionError> {
        let config = self.config;
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

/// Something standing under a raised pass: where the pass was stopped and how far the proximity
/// channel had risen above the sound surface's level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Obstruction {
    /// Mean P of the latest [`GUARD_MEAN_SAMPLES`] samples above the pass's first
    /// [`GUARD_REFERENCE_SAMPLES`] (their median), counts.
    pub(super) rise_counts: f64,
    /// Where the arm was along the pass's line when the guard stopped it, mm from `line_start`.
    pub(super) at_mm: f64,
}

/// Samples at the start of a guarded pass whose median is the sound surface's level.
pub(super) const GUARD_REFERENCE_SAMPLES: usize = 20;
/// Samples averaged for the guard's reading.
pub(super) const GUARD_MEAN_SAMPLES: usize = 4;

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
    pub(super) fn hover_and_record(
        &mut self,
        line_start: [f64; 2],
        to: [f64; 2],
        z: f64,
        speed: f64,
        guard: Option<f64>,
    ) -> Result<(Recorded, Option<Obstruction>), MissionError> {
        let first_sample = self.sensor.samples.len();
        self.stroke = Some(Stroke::new(None, line_start, to));
        let mut reference: Option<f64> = None;
        let mut obstruction: Option<Obstruction> = None;
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
            if let Some(g) = guard {
                let p = &self.sensor.samples[first_sample..];
                if reference.is_none() && p.len() >= GUARD_REFERENCE_SAMPLES {
                    let mut first: Vec<f64> = p[..GUARD_REFERENCE_SAMPLES]
                        .iter()
                        .map(|s| f64::from(s.raw[3]))
                        .collect();
                    first.sort_by(f64::total_cmp);
                    reference = Some(first[GUARD_REFERENCE_SAMPLES / 2]);
                }
                if let Some(r) = reference {
                    let latest = &p[p.len() - GUARD_MEAN_SAMPLES..];
                    let mean = latest.iter().map(|s| f64::from(s.raw[3])).sum::<f64>()
                        / GUARD_MEAN_SAMPLES as f64;
                    if mean - r > g {
                        self.arm.stop();
                        let here = self.arm.here();
                        obstruction = Some(Obstruction {
                            rise_counts: mean - r,
                            at_mm: along(line_start, unit(line_start, to), here),
                        });
                        break;
                    }
                }
            }
            if let Some(e) = self.arm.errors.iter().find(|e| e.seq == seq) {
                return Err(MissionError::Refused {
                    what: "the print check's raised pass".into(),
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
            self.check_progress(deadline, budget, || "the print check's raised pass".into())?;
        }
        // The sensor's samples lag the arm's states: wait (100 ms at most) until one taken
        // after the arm arrived (or was stopped) has come in.
        self.stroke = None;
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
}

/// Samples at each end of a stroke whose proximity level stands for the surface there (0.05 s
/// at 400 Hz, about 0.2 mm at the paper's speed).
const END_SAMPLES: usize = 20;

/// The proximity channel at a stroke's two ends: the medians of its first and last
/// [`END_SAMPLES`], counts; `None` for a stroke of fewer than three times as many samples.
pub(super) fn end_levels(p: &[f64]) -> Option<[f64; 2]> {
    if p.len() < 3 * END_SAMPLES {
        return None;
    }
    let median = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    Some([
        median(&p[..END_SAMPLES]),
        median(&p[p.len() - END_SAMPLES..]),
    ])
}

/// Whether a stroke's two ends read alike: the darker end's signal above the fibre's dark
/// level is at least `share` of the brighter end's. A stroke is planned to start and end on
/// sound surface; one whose ends differ more began or ended on something else (another crack
/// or a print beside the candidate, a bump's flank, a screw head, a crack wider than its
/// stroke). A stroke too short to tell agrees.
pub(super) fn ends_agree(p: &[f64], dark: f64, share: f64) -> bool {
    match end_levels(p) {
        Some([a, b]) => {
            let (lo, hi) = ((a.min(b) - dark).max(0.0), (a.max(b) - dark).max(0.0));
            lo >= share * hi
        }
        None => true,
    }
}

/// `slide` moved `by` mm along `candidate`'s axis, to the side where more of the candidate
/// lies beyond the slide (`by` is a distance; its sign is chosen here); `None` when less than
/// `by` plus `keep` mm of the candidate lies on that side, or either end would leave
/// `workspace`.
pub(super) fn slide_along(
    slide: &crackbot_planner::Slide,
    candidate: &Candidate,
    workspace: &Workspace,
    by: f64,
    keep: f64,
) -> Option<crackbot_planner::Slide> {
    let u = candidate.axis();
    let mid = [
        (slide.start_mm[0] + slide.end_mm[0]) / 2.0,
        (slide.start_mm[1] + slide.end_mm[1]) / 2.0,
    ];
    let t = (mid[0] - candidate.centre_mm[0]) * u[0] + (mid[1] - candidate.centre_mm[1]) * u[1];
    let half = candidate.length_mm / 2.0;
    let (room, sign) = if half - t >= half + t {
        (half - t, 1.0)
    } else {
        (half + t, -1.0)
    };
    if room.is_nan() || room < by + keep {
        return None;
    }
    let shift = |p: [f64; 2]| [p[0] + sign * by * u[0], p[1] + sign * by * u[1]];
    let (start, end) = (shift(slide.start_mm), shift(slide.end_mm));
    (workspace.contains(start) && workspace.contains(end)).then(|| crackbot_planner::Slide {
        start_mm: start,
        end_mm: end,
        moved_along_mm: slide.moved_along_mm + sign * by,
        ..slide.clone()
    })
}

/// Where one stroke's proximity dip is several dips apart — the smoothed P back within
/// `back_share` of the dip's depth of the sound surface's level for at least `gap_mm` of travel
/// between them (a second crack or a print beside the candidate) — the samples around the dip
/// nearest `near_mm` along the stroke: from halfway across the gap before it to halfway across
/// the gap after it. `None` where there is one dip, or `along` is not one pass (it must run one
/// way). `p` is the proximity channel, `baseline` and `depth` the stroke's dip as the localiser
/// read it (counts).
pub(super) fn nearest_of_several_dips(
    p: &[f64],
    along: &[f64],
    baseline: f64,
    depth: f64,
    near_mm: f64,
    back_share: f64,
    gap_mm: f64,
) -> Option<std::ops::Range<usize>> {
    let n = p.len();
    if n != along.len() || n < 3 || depth.is_nan() || depth <= 0.0 {
        return None;
    }
    let rising = along[n - 1] >= along[0];
    if along
        .windows(2)
        .any(|w| if rising { w[1] < w[0] } else { w[1] > w[0] })
    {
        return None;
    }
    // The localiser's own smoothing.
    let smooth = crackbot_tactile::localise::centred_moving_average(
        p.iter().copied(),
        crackbot_tactile::localise::LocaliseConfig::default().smooth_samples,
    );
    let low = baseline - 0.5 * depth;
    let back = baseline - back_share * depth;
    // Runs of samples below half depth, as index ranges.
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (i, &v) in smooth.iter().enumerate() {
        if v < low {
            match runs.last_mut() {
                Some(r) if r.1 == i => r.1 = i + 1,
                _ => runs.push((i, i + 1)),
            }
        }
    }
    // Runs joined into dips unless P came back to the surface for `gap_mm` between them.
    let mut dips: Vec<(usize, usize)> = Vec::new();
    for r in runs {
        let apart = dips.last().is_some_and(|d| {
            let up: Vec<usize> = (d.1..r.0).filter(|&i| smooth[i] >= back).collect();
            match (up.first(), up.last()) {
                (Some(&a), Some(&b)) => (along[b] - along[a]).abs() >= gap_mm,
                _ => false,
            }
        });
        match dips.last_mut() {
            Some(d) if !apart => d.1 = r.1,
            _ => dips.push(r),
        }
    }
    if dips.len() < 2 {
        return None;
    }
    let centre = |d: &(usize, usize)| 0.5 * (along[d.0] + along[d.1 - 1]);
    let k = (0..dips.len()).min_by(|&a, &b| {
        (centre(&dips[a]) - near_mm)
            .abs()
            .total_cmp(&(centre(&dips[b]) - near_mm).abs())
    })?;
    let from = if k == 0 {
        0
    } else {
        (dips[k - 1].1 + dips[k].0) / 2
    };
    let to = if k + 1 == dips.len() {
        n
    } else {
        (dips[k].1 + dips[k + 1].0) / 2
    };
    Some(from..to)
}

/// A candidate's own dip where its stroke also crossed a second crack or a print beside it:
/// where the localiser's one dip (`extent`, over the stroke's `samples` at positions `along`)
/// is wider than the candidate (`candidate_width_mm`) by more than
/// [`SEPARATE_DIPS_EXCESS_MM`] and the stroke's dips lie apart
/// (`nearest_of_several_dips`), the samples around the one nearest the candidate (`near_mm`
/// along the stroke) and that dip localised alone. `None` otherwise: the stroke's dip is the
/// candidate's. The mission reports the candidate where this dip lies and judges its print
/// check on these samples; crackbot-research's `examples/replay_ratios.rs` replays it.
pub fn own_dip(
    samples: &[[f64; 4]],
    along: &[f64],
    extent: &crackbot_tactile::localise::CrackExtent,
    candidate_width_mm: f64,
    near_mm: f64,
    config: &crackbot_tactile::localise::LocaliseConfig,
) -> Option<(
    std::ops::Range<usize>,
    crackbot_tactile::localise::CrackExtent,
)> {
    if samples.len() != along.len()
        || extent.width_mm <= candidate_width_mm + SEPARATE_DIPS_EXCESS_MM
    {
        return None;
    }
    let p: Vec<f64> = samples.iter().map(|v| v[3]).collect();
    let r = nearest_of_several_dips(
        &p,
        along,
        extent.baseline_counts,
        extent.depth_counts,
        near_mm,
        SEPARATE_DIPS_BACK_SHARE,
        SEPARATE_DIPS_GAP_MM,
    )?;
    let own = crackbot_tactile::localise::localise(&samples[r.clone()], &along[r.clone()], config)
        .ok()
        .flatten()?;
    Some((r, own))
}

/// The print check's ratio of one raised pass (`raised`: proximity counts and positions on
/// the strokes' axis), the mean over the candidate's strokes of
/// [`print_check::print_ratio`]; a stroke the check cannot use adds its reason to `doubts`.
/// `None` when no stroke gave a ratio.
pub(super) fn raised_ratio(
    strokes: &[(Vec<f64>, Vec<f64>)],
    raised: (&[f64], &[f64]),
    dark: f64,
    doubts: &mut Vec<CrackDoubt>,
) -> Option<RaisedRatio> {
    let (mut ratios, mut floors, mut levels) = (Vec::new(), Vec::new(), Vec::new());
    for (p, x) in strokes {
        match print_check::print_ratios((p, x), raised, dark) {
            Ok(r) => {
                ratios.extend(r.print);
                floors.extend(r.floor);
                levels.push(r.levels);
            }
            Err(e) => doubts.push(CrackDoubt::UnusableStroke {
                reason: e.to_string(),
            }),
        }
    }
    let level = |k: usize| mean(&levels.iter().map(|l| l[k]).collect::<Vec<_>>());
    Some(RaisedRatio {
        print: mean(&ratios)?,
        floor: mean(&floors),
        levels: [level(0)?, level(1)?],
    })
}

/// What one raised pass measured against the candidate's strokes (means over the strokes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RaisedRatio {
    /// [`print_check::print_ratio`].
    pub print: f64,
    /// [`print_check::floor_ratio`], the second estimate (`None` where no stroke gave one).
    pub floor: Option<f64>,
    /// [`print_check::PrintRatios::levels`]: the sound surface's level beside the line in
    /// contact and on the raised pass, counts.
    pub levels: [f64; 2],
}

/// The ratio raised passes decide by: the mean of their print ratios, or where the first was in
/// doubt, of each one's [`RaisedRatio::in_doubt`]; `None` without a pass.
pub(super) fn judged_ratio(measured: &[RaisedRatio], in_doubt: bool) -> Option<f64> {
    let judged = |m: &RaisedRatio| if in_doubt { m.in_doubt() } else { m.print };
    mean(&measured.iter().map(judged).collect::<Vec<_>>())
}

/// The mean of `v`; `None` when it is empty.
fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

impl RaisedRatio {
    /// The estimate a ratio in doubt is judged by: the mean of the two, or the print ratio
    /// alone where there is no floor ratio.
    pub fn in_doubt(&self) -> f64 {
        self.floor.map_or(self.print, |f| 0.5 * (self.print + f))
    }
}

/// Writes one pass in the recordings' CSV layout (the acquisition's columns plus the position).
pub(super) fn save_pass(
    path: &Path,
    samples: &[[f64; 4]],
    positions: &[f64],
    dir: u8,
) -> Result<(), MissionError> {
    use std::io::Write;
    let f = std::fs::File::create(path).map_err(|e| io_err(path, e))?;
    let mut w = std::io::BufWriter::new(f);
    let mut put = || -> std::io::Result<()> {
        writeln!(w, "d1,d2,d3,p,direction,x_mm")?;
        for (s, x) in samples.iter().zip(positions) {
            writeln!(w, "{},{},{},{},{dir},{x:.4}", s[0], s[1], s[2], s[3])?;
        }
        w.flush()
    };
    put().map_err(|e| io_err(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn of_two_separate_dips_the_one_nearest_the_candidate_is_taken() {
        // 10 mm at 0.01 mm a sample; the surface reads 500, dips 200 deep.
        let along: Vec<f64> = (0..1000).map(|i| f64::from(i) * 0.01).collect();
        let trace = |dips: &[(f64, f64, f64)]| -> Vec<f64> {
            along
                .iter()
                .map(|&x| {
                    dips.iter().fold(
                        500.0,
                        |p: f64, &(a, b, level)| {
                            if (a..b).contains(&x) {
                                p.min(level)
                            } else {
                                p
                            }
                        },
                    )
                })
                .collect()
        };
        let two = trace(&[(2.5, 3.5, 300.0), (6.5, 7.5, 300.0)]);
        let r = nearest_of_several_dips(&two, &along, 500.0, 200.0, 7.2, 0.15, 0.5).unwrap();
        assert!(along[r.start] > 3.5 && along[r.start] < 6.5, "{r:?}");
        assert_eq!(r.end, along.len());
        let r = nearest_of_several_dips(&two, &along, 500.0, 200.0, 2.0, 0.15, 0.5).unwrap();
        assert_eq!(r.start, 0);
        assert!(along[r.end - 1] > 3.5 && along[r.end - 1] < 6.5, "{r:?}");
        // One dip, or two whose middle stays below the surface (a wide crack's floor coming
        // back up part way), or a gap shorter than asked: one dip.
        let one = trace(&[(4.0, 6.0, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&one, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        let wide = trace(&[(2.5, 7.5, 450.0), (2.5, 3.5, 300.0), (6.5, 7.5, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&wide, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        let close = trace(&[(2.5, 4.7, 300.0), (5.0, 7.5, 300.0)]);
        assert_eq!(
            nearest_of_several_dips(&close, &along, 500.0, 200.0, 5.0, 0.15, 0.5),
            None
        );
        // Positions that turn back are not one pass.
        let mut back = along.clone();
        back[500] = 0.0;
        assert_eq!(
            nearest_of_several_dips(&two, &back, 500.0, 200.0, 7.2, 0.15, 0.5),
            None
        );
        // Nothing to read: no depth, lengths that differ.
        assert_eq!(
            nearest_of_several_dips(&two, &along, 500.0, 0.0, 7.2, 0.15, 0.5),
            None
        );
        assert_eq!(
            nearest_of_several_dips(&two[1..], &along, 500.0, 200.0, 7.2, 0.15, 0.5),
            None
        );
    }

    #[test]
    fn a_stroke_whose_ends_read_unlike_each_other_disagrees() {
        let dark = 280.0;
        let stroke = |a: f64, b: f64| {
            let mut p = vec![a; 40];
            p.extend(vec![300.0; 40]);
            p.extend(vec![b; 40]);
            p
        };
        assert!(ends_agree(&stroke(500.0, 480.0), dark, 0.6));
        assert!(ends_agree(&stroke(500.0, 420.0), dark, 0.6)); // 140 of 220
        assert!(!ends_agree(&stroke(500.0, 400.0), dark, 0.6)); // 120 of 220
        assert!(!ends_agree(&stroke(330.0, 500.0), dark, 0.6));
        // Below the dark level counts as no signal; too short to tell agrees.
        assert!(!ends_agree(&stroke(270.0, 500.0), dark, 0.6));
        assert!(ends_agree(&[300.0; 50], dark, 0.6));
        assert_eq!(end_levels(&[1.0; 59]), None);
        let mut p = vec![1.0; 30];
        p.extend(vec![2.0; 30]);
        assert_eq!(end_levels(&p), Some([1.0, 2.0]));
    }

    #[test]
    fn a_slide_moves_along_its_candidate_to_the_longer_side_and_stays_inside() {
        let ws = Workspace::new(0.0, 200.0, 0.0, 100.0).expect("workspace");
        // A crack along x from 40 to 80 mm at y = 50, slid across at x = 50 (10 mm from its
        // start, 30 from its end).
        let cand = Candidate::from_axis(7, [[40.0, 50.0], [80.0, 50.0]], Some(1.0), 0.9);
        let slide = crackbot_planner::Slide {
            candidates: vec![7],
            row: None,
            start_mm: [50.0, 40.0],
            end_mm: [50.0, 60.0],
            stroke_mm: 20.0,
            passes: 1,
            speed_mm_s: 4.6,
            duration_s: 4.3,
            sound_run_mm: Some([5.0, 5.0]),
            shifted_mm: 0.0,
            clipped: false,
            moved_along_mm: 0.0,
        };
        let moved = slide_along(&slide, &cand, &ws, 4.0, 1.0).expect("room on the far side");
        assert_eq!(moved.start_mm, [54.0, 40.0]);
        assert_eq!(moved.end_mm, [54.0, 60.0]);
        assert_eq!(moved.moved_along_mm, 4.0);
        assert_eq!(moved.stroke_mm, 20.0);
        // Slid across near its far end: it moves back towards the start.
        let near_end = crackbot_planner::Slide {
            start_mm: [78.0, 40.0],
            end_mm: [78.0, 60.0],
            ..slide.clone()
        };
        let back = slide_along(&near_end, &cand, &ws, 4.0, 1.0).expect("room behind");
        assert_eq!(back.start_mm, [74.0, 40.0]);
        // A short candidate has no room; nor has a slide at the workspace's edge.
        let short = Candidate::from_axis(8, [[48.0, 50.0], [52.0, 50.0]], None, 0.9);
        assert!(slide_along(&slide, &short, &ws, 4.0, 1.0).is_none());
        let edge = crackbot_planner::Slide {
            start_mm: [50.0, 0.0],
            end_mm: [50.0, 20.0],
            ..slide.clone()
        };
        let along_y = Candidate::from_axis(9, [[50.0, 10.0], [50.0, 12.0]], None, 0.9);
        assert!(slide_along(&edge, &along_y, &ws, 4.0, 1.0).is_none());
    }

    #[test]
    pub(super) fn rows_are_cut_into_stroke_long_pieces_without_a_short_tail() {
        let x: Vec<f64> = (0..=350).map(|i| f64::from(i) * 0.1).collect(); // 0–35 mm
                                                                           // 0–16, then 16–35: the 3 mm tail joins the second piece.
        assert_eq!(split_by_travel(&x, 16.0), vec![(0, 160), (160, 351)]);
        let x: Vec<f64> = (0..=300).map(|i| f64::from(i) * 0.1).collect(); // 0–30 mm
        assert_eq!(split_by_travel(&x, 16.0), vec![(0, 160), (160, 301)]);
        let x: Vec<f64> = (0..=450).map(|i| f64::from(i) * 0.1).collect(); // 0–45 mm
        assert_eq!(
            split_by_travel(&x, 16.0),
            vec![(0, 160), (160, 320), (320, 451)]
        );
        assert!(split_by_travel(&[], 16.0).is_empty());
    }

    #[test]
    fn passes_in_doubt_are_judged_by_both_estimates_and_others_by_the_print_ratio() {
        let pass = |print: f64, floor: Option<f64>| RaisedRatio {
            print,
            floor,
            levels: [450.0, 270.0],
        };
        let passes = [pass(0.86, Some(1.0)), pass(0.84, None)];
        // Not in doubt: the print ratios' mean.
        assert!((judged_ratio(&passes, false).unwrap() - 0.85).abs() < 1e-12);
        // In doubt: each pass's mean of the two (the print ratio where there is no floor ratio).
        assert!((judged_ratio(&passes, true).unwrap() - (0.93 + 0.84) / 2.0).abs() < 1e-12);
        assert_eq!(judged_ratio(&[], true), None);
    }
}
