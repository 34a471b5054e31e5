//! The simulated arm and finger over a scene, advanced one sensor sample (1/400 s) at a time.
//!
//! The world is stepped by the emulated sensor's 400 Hz ticks ([`crate::sensor`]), so every
//! sensor sample and the arm pose of the same tick are simulated together: the ground truth
//! that the robot's clock synchronisation is tested against.
//!
//! Commands are checked against the [`Limits`] whoever sends them: a point outside the
//! workspace or a speed above the limits is refused ([`Refusal`]) and nothing moves.

use crackbot_sim::run::{SlideLine, SlideSim, SAMPLE_RATE_HZ};
use crackbot_sim::{Integrator, Scene, SensorParams, SimError, Surface};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::arm::Mode;
use crate::command::Checked;
use crate::limits::{Limits, Refusal, MAX_MOVE_HEIGHT_MM, MIN_MOVE_HEIGHT_MM};

/// Height of the finger above the plate while it travels between slides, mm.
pub const TRAVEL_HEIGHT_MM: f64 = 5.0;

/// Standard deviation of the noise on the lifted finger's deformation channels, counts.
const LIFTED_NOISE_COUNTS: f64 = 0.6;

/// One tick's output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    /// The world's tick (1/400 s each) after this step.
    pub tick: u64,
    /// Channel values for the ADC (D1, D2, D3, P), counts.
    pub counts: [f64; 4],
    /// Arm pose, mm `[x, y, z]` in the plate frame (z: height of the finger above the plate).
    pub pose: [f64; 3],
    /// Arm velocity, mm/s.
    pub velocity: [f64; 3],
    /// What the arm is doing.
    pub mode: Mode,
    /// Fraction of the current slide done, 0–1.
    pub progress: f64,
    /// A slide that ended at this tick.
    pub finished: Option<u32>,
}

#[derive(Debug, Clone, Copy)]
struct PendingSlide {
    id: u32,
    start: [f64; 2],
    end: [f64; 2],
    speed: f64,
}

#[derive(Debug)]
enum Activity {
    Idle,
    Stopped,
    Moving {
        from: [f64; 2],
        to: [f64; 2],
        /// Height of the tip above the plate's plane during the move, mm.
        z: f64,
        ticks: u64,
        done: u64,
        then: Option<PendingSlide>,
    },
    Sliding {
        id: u32,
        /// Start and direction of the simulation's first stroke (its arm coordinate's origin).
        start: [f64; 2],
        dir: [f64; 2],
        sim: Box<SlideSim>,
        done: u64,
        ticks: u64,
        /// This stroke's start and end (for continuing back along the same line).
        from: [f64; 2],
        to: [f64; 2],
        speed: f64,
    },
}

/// The finger's simulation after a slide, kept so that a slide straight back along the same
/// line continues it (the authors slid forth and back without lifting the finger).
#[derive(Debug)]
struct Resting {
    start: [f64; 2],
    dir: [f64; 2],
    sim: Box<SlideSim>,
    from: [f64; 2],
    to: [f64; 2],
    speed: f64,
}

/// A slide whose line the finger is pressed on while another arm drives it
/// ([`World::step_following`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pressed {
    /// Start of the slide, mm.
    pub start: [f64; 2],
    /// End of the slide, mm.
    pub end: [f64; 2],
    /// Its speed, mm/s.
    pub speed_mm_s: f64,
}

/// The finger's simulation on the line another arm presses it along.
#[derive(Debug)]
struct Following {
    /// The line's ends (a slide back along it keeps the simulation).
    ends: [[f64; 2]; 2],
    start: [f64; 2],
    dir: [f64; 2],
    sim: Box<SlideSim>,
}

/// The simulated arm, finger and sensor over one scene.
#[derive(Debug)]
pub struct World {
    surface: Surface,
    reflectivity: f64,
    sensor: SensorParams,
    limits: Limits,
    travel_speed: f64,
    pose: [f64; 3],
    velocity: [f64; 3],
    tick: u64,
    activity: Activity,
    /// Deformation channels with the finger lifted (travel, idle), counts. Its proximity
    /// channel sees the surface below it ([`crackbot_sim::run::hover_view`]).
    lifted: [f64; 3],
    /// The way the arm last moved (the proximity fibre looks ahead along it).
    heading: [f64; 2],
    rng: ChaCha8Rng,
    seed: u64,
    slides: u32,
    resting: Option<Resting>,
    following: Option<Following>,
}

impl World {
    /// The arm over `scene`, parked at the workspace's lower corner, noise drawn from `seed`.
    pub fn new(scene: &Scene, seed: u64) -> Result<Self, SimError> {
        scene.validate()?;
        let limits = Limits::of_scene(scene);
        let surface = scene.surface();
        let reflectivity = scene.plate.material.reflectivity;
        // The lifted finger's deformation channels: what a slide's first sample reads (at rest,
        // before it moves) on a clean spot of the plate. Its proximity channel is worked out at
        // each pose from the surface below (`lifted_counts`).
        let probe = SlideSim::new(
            &Surface::flat([200.0, 100.0]),
            reflectivity,
            &SlideLine {
                start: [0.0, 0.0],
                direction: [1.0, 0.0],
                stroke_mm: 10.0,
                speed_mm_s: 1.0,
            },
            &scene.sensor,
            Integrator::default(),
            seed,
        )?
        .next_sample()?;
        Ok(World {
            surface,
            reflectivity,
            sensor: scene.sensor.clone(),
            limits,
            travel_speed: scene.manipulator.travel_speed_mm_s,
            pose: [limits.min_mm[0], limits.min_mm[1], TRAVEL_HEIGHT_MM],
            velocity: [0.0; 3],
            tick: 0,
            activity: Activity::Idle,
            lifted: [probe.counts[0], probe.counts[1], probe.counts[2]],
            heading: [1.0, 0.0],
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x5eed),
            seed,
            slides: 0,
            resting: None,
            following: None,
        })
    }

    /// The limits every command is checked against.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Current pose, mm.
    pub fn pose(&self) -> [f64; 3] {
        self.pose
    }

    /// Ticks simulated so far.
    pub fn tick_count(&self) -> u64 {
        self.tick
    }

    /// The current mode.
    pub fn mode(&self) -> Mode {
        match &self.activity {
            Activity::Idle => Mode::Idle,
            Activity::Stopped => Mode::Stopped,
            Activity::Moving { then: Some(p), .. } => Mode::Sliding(p.id),
            Activity::Moving { .. } => Mode::Moving,
            Activity::Sliding { id, .. } => Mode::Sliding(*id),
        }
    }

    /// Whether the arm is busy with a command.
    pub fn is_busy(&self) -> bool {
        matches!(
            self.activity,
            Activity::Moving { .. } | Activity::Sliding { .. }
        )
    }

    /// Travel to `to` at `speed` with the tip held `z` mm above the plate's plane (the finger
    /// goes to that height first, then moves level). Replaces what the arm was doing.
    pub fn move_to(&mut self, to: [f64; 2], z: f64, speed: f64) -> Result<(), Refusal> {
        self.limits.check_point("target", to)?;
        Limits::check_speed("travel", speed, self.limits.max_travel_speed_mm_s)?;
        if !(MIN_MOVE_HEIGHT_MM..=MAX_MOVE_HEIGHT_MM).contains(&z) {
            return Err(Refusal::OutOfRange {
                what: "move height",
                value: z,
                min: MIN_MOVE_HEIGHT_MM,
                max: MAX_MOVE_HEIGHT_MM,
            });
        }
        // The finger leaves the surface: a later slide starts afresh.
        self.resting = None;
        self.start_move(to, z, speed, None);
        Ok(())
    }

    /// Slide `id` from `start` to `end` at `speed`, travelling to `start` first (at the scene's
    /// travel speed). Replaces what the arm was doing.
    pub fn slide(
        &mut self,
        id: u32,
        start: [f64; 2],
        end: [f64; 2],
        speed: f64,
    ) -> Result<(), Refusal> {
        self.limits.check_point("slide start", start)?;
        self.limits.check_point("slide end", end)?;
        Limits::check_speed("slide", speed, self.limits.max_slide_speed_mm_s)?;
        let len = (end[0] - start[0]).hypot(end[1] - start[1]);
        if !(0.5..=crackbot_sim::run::MAX_STROKE_MM).contains(&len) {
            return Err(Refusal::OutOfRange {
                what: "slide length",
                value: len,
                min: 0.5,
                max: crackbot_sim::run::MAX_STROKE_MM,
            });
        }
        let pending = PendingSlide {
            id,
            start,
            end,
            speed,
        };
        let speed = self.travel_speed.min(self.limits.max_travel_speed_mm_s);
        self.start_move(start, TRAVEL_HEIGHT_MM, speed, Some(pending));
        Ok(())
    }

    /// Runs a command checked by [`crate::command::check`]; `Some(id)`: slide `id` started.
    pub fn apply(&mut self, command: Checked) -> Result<Option<u32>, Refusal> {
        match command {
            Checked::Heartbeat => Ok(None),
            Checked::Stop => {
                self.stop();
                Ok(None)
            }
            Checked::Move(m) => self.move_to(m.to, m.z_mm, m.speed_mm_s).map(|()| None),
            Checked::Slide(s) => self
                .slide(s.id, s.start, s.end, s.speed_mm_s)
                .map(|()| Some(s.id)),
        }
    }

    /// Stops where it is; the next command starts from here.
    pub fn stop(&mut self) {
        self.activity = Activity::Stopped;
        self.pose[2] = TRAVEL_HEIGHT_MM;
        self.velocity = [0.0; 3];
    }

    fn start_move(&mut self, to: [f64; 2], z: f64, speed: f64, then: Option<PendingSlide>) {
        let from = [self.pose[0], self.pose[1]];
        let dist = (to[0] - from[0]).hypot(to[1] - from[1]);
        let ticks = (dist / speed * SAMPLE_RATE_HZ).ceil() as u64;
        if dist > 1e-9 {
            self.heading = [(to[0] - from[0]) / dist, (to[1] - from[1]) / dist];
        }
        self.pose[2] = z;
        self.activity = Activity::Moving {
            from,
            to,
            z,
            ticks,
            done: 0,
            then,
        };
    }

    fn begin_slide(&mut self, p: PendingSlide) -> Result<(), SimError> {
        let d = [p.end[0] - p.start[0], p.end[1] - p.start[1]];
        let len = d[0].hypot(d[1]);
        let dir = [d[0] / len, d[1] / len];
        self.heading = dir;
        // Straight back (or forth again) along the line just slid: the finger never left the
        // surface, so its simulation goes on (the wait between the commands is a pause at the
        // stroke's end).
        if let Some(r) = self.resting.take() {
            let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-3;
            if close(p.start, r.to) && close(p.end, r.from) && (p.speed - r.speed).abs() < 1e-9 {
                self.slides += 1;
                let ticks = (r.sim.slide_time() / 2.0 * SAMPLE_RATE_HZ).ceil() as u64;
                self.activity = Activity::Sliding {
                    id: p.id,
                    start: r.start,
                    dir: r.dir,
                    sim: r.sim,
                    done: 0,
                    ticks,
                    from: p.start,
                    to: p.end,
                    speed: p.speed,
                };
                return Ok(());
            }
        }
        let sim = self.contact_sim(p.start, p.end, p.speed)?;
        // One stroke, there only (`slide_time` is forth and back).
        let ticks = (sim.slide_time() / 2.0 * SAMPLE_RATE_HZ).ceil() as u64;
        self.activity = Activity::Sliding {
            id: p.id,
            start: p.start,
            dir,
            sim: Box::new(sim),
            done: 0,
            ticks,
            from: p.start,
            to: p.end,
            speed: p.speed,
        };
        Ok(())
    }

    /// The channels with the finger off the surface at the current pose: the deformation
    /// channels at rest, the proximity channel seeing the surface below (noise added).
    fn lifted_counts(&mut self) -> [f64; 4] {
        let o = &self.sensor.optics;
        let view = crackbot_sim::run::hover_view(
            o,
            &self.surface,
            self.reflectivity,
            [self.pose[0], self.pose[1]],
            self.heading,
            self.pose[2],
        );
        let p = o.proximity_dark_counts + o.proximity_peak_counts * view.intensity;
        let p_noise = o.noise_counts[3].max(0.0);
        let sat = o.saturation_counts;
        let mut c = [self.lifted[0], self.lifted[1], self.lifted[2], 0.0];
        for v in &mut c[..3] {
            let z: f64 = rand::Rng::sample(&mut self.rng, rand_distr::StandardNormal);
            *v += LIFTED_NOISE_COUNTS * z;
        }
        let n: f64 = rand::Rng::sample(&mut self.rng, rand_distr::StandardNormal);
        c[3] = o.saturate((p + p_noise * n).min(sat));
        c
    }

    /// A fresh contact simulation along `line` (the printed plates' roughness included).
    fn contact_sim(
        &mut self,
        start: [f64; 2],
        end: [f64; 2],
        speed: f64,
    ) -> Result<SlideSim, SimError> {
        let d = [end[0] - start[0], end[1] - start[1]];
        let len = d[0].hypot(d[1]);
        self.slides += 1;
        let samples = crackbot_sim::plates::calibrated_samples();
        SlideSim::new(
            &self.surface,
            self.reflectivity,
            &SlideLine {
                start,
                direction: [d[0] / len, d[1] / len],
                stroke_mm: len,
                speed_mm_s: speed,
            },
            &self.sensor,
            Integrator::default(),
            self.seed.wrapping_add(u64::from(self.slides)),
        )?
        .with_roughness(
            samples.roughness_rms_mm,
            samples.roughness_correlation_mm,
            self.seed ^ u64::from(self.slides).wrapping_mul(0x9e37_79b9),
        )
    }

    /// Advances one sensor sample with the arm where another arm says it is (`pose`, mm in
    /// the surface frame, z the tip's height): the finger pressed on `pressed`'s line when the
    /// tip is at or below the plate, its contact simulated along the line from the pose's
    /// position on it (a slide back along the same line goes on with the same simulation);
    /// otherwise lifted, its proximity channel seeing the surface below.
    pub fn step_following(
        &mut self,
        pose: [f64; 3],
        pressed: Option<Pressed>,
    ) -> Result<Tick, SimError> {
        self.tick += 1;
        let before = self.pose;
        let counts = match pressed.filter(|_| pose[2] <= 0.05) {
            Some(p) => {
                let same = |f: &Following| {
                    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-3;
                    (close(f.ends[0], p.start) && close(f.ends[1], p.end))
                        || (close(f.ends[0], p.end) && close(f.ends[1], p.start))
                };
                if !self.following.as_ref().is_some_and(same) {
                    let sim = self.contact_sim(p.start, p.end, p.speed_mm_s)?;
                    let len = (p.end[0] - p.start[0]).hypot(p.end[1] - p.start[1]);
                    self.following = Some(Following {
                        ends: [p.start, p.end],
                        start: p.start,
                        dir: [(p.end[0] - p.start[0]) / len, (p.end[1] - p.start[1]) / len],
                        sim: Box::new(sim),
                    });
                }
                let f = self.following.as_mut().expect("set above");
                let along = (pose[0] - f.start[0]) * f.dir[0] + (pose[1] - f.start[1]) * f.dir[1];
                self.heading = f.dir;
                self.pose = [pose[0], pose[1], 0.0];
                f.sim.next_sample_following(along)?.counts
            }
            None => {
                self.following = None;
                let d = [pose[0] - before[0], pose[1] - before[1]];
                let n = d[0].hypot(d[1]);
                if n > 1e-6 {
                    self.heading = [d[0] / n, d[1] / n];
                }
                self.pose = [pose[0], pose[1], pose[2].max(0.0)];
                self.lifted_counts()
            }
        };
        self.velocity = [0, 1, 2].map(|k| (self.pose[k] - before[k]) * SAMPLE_RATE_HZ);
        Ok(Tick {
            tick: self.tick,
            counts,
            pose: self.pose,
            velocity: self.velocity,
            mode: Mode::Idle,
            progress: 0.0,
            finished: None,
        })
    }

    /// Advances one sensor sample (1/400 s). A simulation failure stops the arm and is returned
    /// (the caller reports it as a fault).
    pub fn step(&mut self) -> Result<Tick, SimError> {
        self.tick += 1;
        let mut finished = None;
        let mut progress = 0.0;
        let counts;
        match &mut self.activity {
            Activity::Idle | Activity::Stopped => {
                self.velocity = [0.0; 3];
                counts = self.lifted_counts();
            }
            Activity::Moving {
                from,
                to,
                z,
                ticks,
                done,
                then,
            } => {
                *done += 1;
                let f = if *ticks == 0 {
                    1.0
                } else {
                    (*done as f64 / *ticks as f64).min(1.0)
                };
                let (from, to, z, then, arrived) = (*from, *to, *z, *then, *done >= *ticks);
                let next = [
                    from[0] + f * (to[0] - from[0]),
                    from[1] + f * (to[1] - from[1]),
                ];
                self.velocity = [
                    (next[0] - self.pose[0]) * SAMPLE_RATE_HZ,
                    (next[1] - self.pose[1]) * SAMPLE_RATE_HZ,
                    0.0,
                ];
                self.pose = [next[0], next[1], z];
                counts = self.lifted_counts();
                if arrived {
                    match then {
                        Some(p) => {
                            if let Err(e) = self.begin_slide(p) {
                                self.stop();
                                return Err(e);
                            }
                        }
                        None => self.activity = Activity::Idle,
                    }
                }
            }
            Activity::Sliding {
                id,
                start,
                dir,
                sim,
                done,
                ticks,
                ..
            } => {
                let s = match sim.next_sample() {
                    Ok(s) => s,
                    Err(e) => {
                        self.stop();
                        return Err(e);
                    }
                };
                *done += 1;
                progress = (*done as f64 / (*ticks).max(1) as f64).min(1.0);
                let x = s.arm_mm;
                self.pose = [start[0] + x * dir[0], start[1] + x * dir[1], 0.0];
                let v = s.arm_velocity_mm_s;
                self.velocity = [v * dir[0], v * dir[1], 0.0];
                counts = s.counts;
                if *done >= *ticks {
                    finished = Some(*id);
                    if let Activity::Sliding {
                        start,
                        dir,
                        sim,
                        from,
                        to,
                        speed,
                        ..
                    } = std::mem::replace(&mut self.activity, Activity::Idle)
                    {
                        self.resting = Some(Resting {
                            start,
                            dir,
                            sim,
                            from,
                            to,
                            speed,
                        });
                    }
                    self.pose[2] = TRAVEL_HEIGHT_MM;
                }
            }
        }
        Ok(Tick {
            tick: self.tick,
            counts,
            pose: self.pose,
            velocity: self.velocity,
            mode: self.mode(),
            progress,
            finished,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> World {
        World::new(&Scene::builtin_default(), 3).expect("default scene")
    }

    #[test]
    fn motion_outside_the_workspace_or_over_the_limits_is_refused_and_nothing_moves() {
        let mut w = world();
        let before = w.pose();
        let err = w
            .move_to([250.0, 50.0], TRAVEL_HEIGHT_MM, 10.0)
            .unwrap_err();
        assert!(matches!(err, Refusal::OutsideWorkspace { .. }), "{err}");
        assert!(err.to_string().contains("250.00"), "{err}");
        let err = w.move_to([50.0, 50.0], TRAVEL_HEIGHT_MM, 1e6).unwrap_err();
        assert!(matches!(err, Refusal::OverSpeed { .. }), "{err}");
        assert!(w.move_to([50.0, 50.0], TRAVEL_HEIGHT_MM, f64::NAN).is_err());
        assert!(w.move_to([f64::NAN, 50.0], TRAVEL_HEIGHT_MM, 10.0).is_err());
        let err = w.slide(1, [10.0, 10.0], [10.0, 150.0], 3.89).unwrap_err();
        assert!(err.to_string().contains("slide end"), "{err}");
        let err = w.slide(1, [10.0, 10.0], [20.0, 10.0], 100.0).unwrap_err();
        assert!(matches!(err, Refusal::OverSpeed { .. }), "{err}");
        let err = w.slide(1, [10.0, 10.0], [10.1, 10.0], 3.89).unwrap_err();
        assert!(matches!(err, Refusal::OutOfRange { .. }), "{err}");
        for _ in 0..10 {
            w.step().expect("step");
        }
        assert_eq!(w.pose(), before);
        assert_eq!(w.mode(), Mode::Idle);
    }

    #[test]
    fn a_slide_travels_to_its_start_then_slides_to_its_end_in_the_expected_time() {
        let mut w = world();
        let (start, end, speed) = ([30.0, 20.0], [30.0, 36.0], 4.0);
        w.slide(7, start, end, speed).expect("slide");
        let mut sliding_ticks = 0u64;
        let mut finished = None;
        let mut last = w.pose();
        for _ in 0..40_000 {
            let t = w.step().expect("step");
            for v in t.counts {
                assert!(v.is_finite());
            }
            // Never outside the workspace, never faster than the limits.
            let step = (t.pose[0] - last[0]).hypot(t.pose[1] - last[1]) * SAMPLE_RATE_HZ;
            assert!(step <= w.limits().max_travel_speed_mm_s + 1e-6, "{step}");
            last = t.pose;
            if t.mode == Mode::Sliding(7) && t.pose[2] == 0.0 {
                sliding_ticks += 1;
                if t.finished.is_none() {
                    assert!((t.pose[0] - 30.0).abs() < 1e-9);
                }
            }
            if let Some(id) = t.finished {
                finished = Some(id);
                break;
            }
        }
        assert_eq!(finished, Some(7));
        let expected = 16.0 / speed * SAMPLE_RATE_HZ;
        assert!(
            (sliding_ticks as f64 - expected).abs() < 0.1 * expected,
            "{sliding_ticks} ticks, expected about {expected}"
        );
        assert!((w.pose()[1] - 36.0).abs() < 0.5, "{:?}", w.pose());
        assert_eq!(w.mode(), Mode::Idle);
    }

    #[test]
    fn a_slide_straight_back_continues_the_finger_without_lifting_it() {
        let mut w = world();
        let (a, b) = ([30.0, 20.0], [30.0, 36.0]);
        let run = |w: &mut World, id: u32| -> (u64, [f64; 4], [f64; 4]) {
            let (mut n, mut first, mut last) = (0u64, None, [0.0; 4]);
            for _ in 0..40_000 {
                let t = w.step().expect("step");
                if t.mode == Mode::Sliding(id) && t.pose[2] == 0.0 {
                    n += 1;
                    first.get_or_insert(t.counts);
                    last = t.counts;
                }
                if t.finished == Some(id) {
                    return (n, first.expect("slid"), last);
                }
            }
            panic!("slide {id} never ended");
        };
        w.slide(1, a, b, 4.6).expect("forth");
        let (n1, _, end1) = run(&mut w, 1);
        w.slide(2, b, a, 4.6).expect("back");
        // No travel: one hand-over tick, then it slides on from where the finger is.
        let t = w.step().expect("step");
        assert_eq!(t.mode, Mode::Sliding(2));
        assert!((t.pose[1] - 36.0).abs() < 1e-9, "{:?}", t.pose);
        let (n2, start2, _) = run(&mut w, 2);
        assert!((n1 as i64 - n2 as i64 - 1).abs() <= 1, "{n1} vs {n2}");
        // The signal goes on from where the stroke ended (no restart from rest).
        for c in 0..4 {
            assert!(
                (start2[c] - end1[c]).abs() < 60.0,
                "channel {c}: {end1:?} → {start2:?}"
            );
        }
        assert!((w.pose()[1] - 20.0).abs() < 0.5, "{:?}", w.pose());
    }

    #[test]
    fn stop_halts_the_arm_where_it_is() {
        let mut w = world();
        w.move_to([150.0, 80.0], TRAVEL_HEIGHT_MM, 50.0)
            .expect("move");
        for _ in 0..100 {
            w.step().expect("step");
        }
        w.stop();
        let here = w.pose();
        for _ in 0..100 {
            let t = w.step().expect("step");
            assert_eq!(t.mode, Mode::Stopped);
        }
        assert_eq!(w.pose(), here);
        assert!(here[0] > 0.0 && here[0] < 150.0);
    }

    /// The proximity channel along a level move at height `z` from x = 50 to 130 mm at y = 50,
    /// as `(x, P)` per tick.
    fn raised_pass(w: &mut World, z: f64) -> Vec<(f64, f64)> {
        w.move_to([50.0, 50.0], z, 50.0).expect("to the start");
        while w.is_busy() {
            w.step().expect("step");
        }
        w.move_to([130.0, 50.0], z, 20.0).expect("the pass");
        let mut out = Vec::new();
        while w.is_busy() {
            let t = w.step().expect("step");
            assert_eq!(t.pose[2], z);
            out.push((t.pose[0], t.counts[3]));
        }
        out
    }

    /// The dip's depth over `[x0, x1]` as a share of the flat surface's signal above dark.
    fn dip_share(pass: &[(f64, f64)], x0: f64, x1: f64, dark: f64) -> f64 {
        let flat: Vec<f64> = pass
            .iter()
            .filter(|(x, _)| *x < 55.0)
            .map(|(_, p)| *p)
            .collect();
        let flat = flat.iter().sum::<f64>() / flat.len() as f64;
        let floor = pass
            .iter()
            .filter(|(x, _)| (x0..=x1).contains(x))
            .map(|(_, p)| *p)
            .fold(f64::INFINITY, f64::min);
        (flat - floor) / (flat - dark)
    }

    #[test]
    fn a_raised_finger_sees_ink_darken_alike_at_every_height_and_a_crack_less_higher_up() {
        use crackbot_sim::Feature;
        let mut scene = Scene::builtin_default();
        scene.sensor.optics.noise_counts = [0.0; 4];
        scene.features = vec![
            Feature::Decoy {
                path: vec![[70.0, 30.0], [70.0, 70.0]],
                width_mm: 3.0,
                reflectivity: 0.3,
            },
            Feature::Crack {
                path: vec![[110.0, 30.0], [110.0, 70.0]],
                width_mm: 3.0,
                depth_mm: 2.5,
                edge_radius_mm: 0.2,
                wall_angle_deg: 90.0,
            },
        ];
        let dark = scene.sensor.optics.proximity_dark_counts;
        let mut w = World::new(&scene, 5).expect("scene");
        let (low, high) = (raised_pass(&mut w, 1.0), raised_pass(&mut w, 3.0));
        // The fibre looks 1.8 mm ahead of the tip: the marks show up that much early.
        let (ink_low, ink_high) = (
            dip_share(&low, 64.0, 70.0, dark),
            dip_share(&high, 64.0, 70.0, dark),
        );
        let (crack_low, crack_high) = (
            dip_share(&low, 104.0, 110.0, dark),
            dip_share(&high, 104.0, 110.0, dark),
        );
        assert!((ink_low - 0.7).abs() < 0.03, "{ink_low}");
        assert!((ink_high - ink_low).abs() < 0.03, "{ink_low} {ink_high}");
        assert!(crack_low > 0.5, "{crack_low}");
        assert!(crack_high < 0.85 * crack_low, "{crack_low} {crack_high}");
        // Heights the arm must not hold are refused.
        for z in [0.0, 0.2, 60.0, f64::NAN] {
            let err = w.move_to([60.0, 50.0], z, 20.0).unwrap_err();
            assert!(matches!(err, Refusal::OutOfRange { .. }), "{err}");
        }
    }
}

#[cfg(test)]
mod following_tests {
    use super::*;

    /// A slide forth and back along one line, the pose given sample by sample as a real arm
    /// would report it (moving 4 mm/s, pressed 1 mm), then lifted: finite counts, no error,
    /// each sample quick.
    #[test]
    fn the_finger_follows_a_reported_pose_forth_and_back_along_a_slide() {
        let mut w = World::new(&Scene::builtin_default(), 3).expect("default scene");
        let (a, b) = ([38.0, 22.0], [38.0, 38.0]);
        let pressed = Some(Pressed {
            start: a,
            end: b,
            speed_mm_s: 4.0,
        });
        let mut slowest = 0.0f64;
        let mut run = |w: &mut World, from: [f64; 2], to: [f64; 2], p: Option<Pressed>| {
            let n = 1600;
            for k in 0..=n {
                let f = k as f64 / n as f64;
                let pose = [
                    from[0] + f * (to[0] - from[0]),
                    from[1] + f * (to[1] - from[1]),
                    if p.is_some() { -1.0 } else { 5.0 },
                ];
                let t = std::time::Instant::now();
                let tick = w.step_following(pose, p).expect("step");
                slowest = slowest.max(t.elapsed().as_secs_f64());
                assert!(tick.counts.iter().all(|c| c.is_finite()), "{tick:?}");
            }
        };
        run(&mut w, a, b, pressed);
        run(
            &mut w,
            b,
            a,
            pressed.map(|p| Pressed {
                start: b,
                end: a,
                ..p
            }),
        );
        run(&mut w, a, [100.0, 50.0], None);
        eprintln!("slowest sample {:.1} ms", slowest * 1e3);
    }
}
