//! A Cartesian arm driven by a stream of targets, as a pure state machine: what the ROS 2 arm
//! does, without DDS, so every decision is tested with made-up times and poses.
//!
//! A checked command becomes a [`Path`] of straight legs in the surface frame: a move rises or
//! sinks to its height in place, then travels level; a slide rises to the travel height, travels
//! to its start, presses the finger in (1 mm, or the commanded depth), strokes to its end at the
//! commanded speed and holds there ([`CartesianSettings::hold_s`]) so that a slide straight back
//! goes on without lifting, then lifts. [`CartesianArm::tick`] gives the target to publish now,
//! each one checked by the [`TargetGuard`] first; [`CartesianArm::report`] takes the arm's pose.
//! A stop ends the target stream at once (one last target holds the arm where it is); a stale,
//! drifting, broken or flooding pose stream is a fault ([`ArmFault`]) that stops it too.

use crackbot_link::Contact;

use crate::arm::{ArmState, Mode};
use crate::command::Checked;
use crate::limits::{Limits, Refusal, MAX_MOVE_HEIGHT_MM};
use crate::motion::guard::{divergence, staleness, ArmFault, Envelope, TargetGuard};
use crate::motion::path::{Leg, LegKind, Path};

/// How deep a slide presses the finger when the command asks for a force (a position-controlled
/// arm cannot hold one), mm.
pub const DEFAULT_PRESS_MM: f64 = 1.0;

/// How a Cartesian arm moves and what it tolerates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartesianSettings {
    /// The workspace and speed limits commands are checked against.
    pub limits: Limits,
    /// Speed of travel between slides, mm/s.
    pub travel_speed_mm_s: f64,
    /// Height of the finger while it travels between slides, mm.
    pub travel_height_mm: f64,
    /// Speed of pressing the finger in and lifting it, mm/s.
    pub approach_speed_mm_s: f64,
    /// Acceleration of every leg, mm/s².
    pub max_accel_mm_s2: f64,
    /// How long the finger stays pressed at a slide's end for a slide straight back, s.
    pub hold_s: f64,
    /// No pose from the arm for this long is a fault, s.
    pub stale_after_s: f64,
    /// The arm this far from its target is a fault, mm.
    pub divergence_mm: f64,
    /// More pose reports than this in one period is a flood.
    pub max_reports_per_tick: usize,
    /// Contact force over this is a fault, N (when the arm reports a wrench).
    pub max_force_n: f64,
}

impl CartesianSettings {
    /// Defaults for `limits`: travel at 50 mm/s (or the limit) 5 mm up, press at 5 mm/s,
    /// 500 mm/s², hold 1 s, 250 ms without a pose or 10 mm off target is a fault.
    pub fn new(limits: Limits) -> Self {
        CartesianSettings {
            limits,
            travel_speed_mm_s: limits.max_travel_speed_mm_s.min(50.0),
            travel_height_mm: 5.0,
            approach_speed_mm_s: 5.0,
            max_accel_mm_s2: 500.0,
            hold_s: 1.0,
            stale_after_s: 0.25,
            divergence_mm: 10.0,
            max_reports_per_tick: 50,
            max_force_n: 10.0,
        }
    }

    /// The box no target may leave: the workspace, from the deepest press to the highest move.
    pub fn envelope(&self) -> Envelope {
        let l = &self.limits;
        Envelope {
            min_mm: [l.min_mm[0], l.min_mm[1], -crate::command::MAX_DEPTH_MM],
            max_mm: [l.max_mm[0], l.max_mm[1], MAX_MOVE_HEIGHT_MM],
            max_speed_mm_s: l.max_travel_speed_mm_s.max(l.max_slide_speed_mm_s),
            max_accel_mm_s2: self.max_accel_mm_s2,
        }
    }
}

/// A slide's line on the plate, for a simulated finger that follows the arm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlideOnPlate {
    /// The slide's id.
    pub id: u32,
    /// Start, mm.
    pub start: [f64; 2],
    /// End, mm.
    pub end: [f64; 2],
    /// Speed, mm/s.
    pub speed_mm_s: f64,
}

/// A pose the arm reported, checked (finite, right frame), in the surface frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report {
    /// When it arrived, s on the controller's clock.
    pub t_s: f64,
    /// The tool's point, mm.
    pub pose_mm: [f64; 3],
}

#[derive(Debug, Clone)]
enum Task {
    Move,
    Slide(SlideOnPlate),
    /// The lift after a slide's hold (not commanded: the link reports the arm idle).
    Lift,
}

#[derive(Debug, Clone)]
enum Activity {
    /// No command yet: idle, streaming nothing.
    Waiting,
    /// Holding the last target (streaming it), since this time.
    Holding { since: f64, pressed: bool },
    /// Following a path started at `started`.
    Running {
        path: Path,
        started: f64,
        task: Task,
    },
    /// Stopped: no target stream.
    Stopped,
}

/// The Cartesian arm's state machine.
#[derive(Debug, Clone)]
pub struct CartesianArm {
    settings: CartesianSettings,
    guard: TargetGuard,
    activity: Activity,
    /// The last published target, mm.
    target: Option<[f64; 3]>,
    /// The newest pose and the one before it.
    measured: Option<Report>,
    previous: Option<Report>,
    finished: Vec<u32>,
    fault: Option<ArmFault>,
    /// The slide the finger is on (pressed), if any.
    on_plate: Option<SlideOnPlate>,
    progress: f64,
    /// The one target a stop publishes: where the arm is.
    hold_once: Option<[f64; 3]>,
    /// Whether a slide is on its stroke: before that it is lifting out of the last slide's
    /// hold, travelling and pressing in, reported as Moving, so that the link's "Sliding and
    /// down" means this slide's stroke only, the finger already pressed in.
    engaged: bool,
}

/// What a tick asks the DDS side to do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Publish {
    /// Publish this target, mm in the surface frame.
    Target([f64; 3]),
    /// Nothing (stopped, faulted, or no command yet).
    Nothing,
}

impl CartesianArm {
    /// An arm that has heard nothing and streams nothing.
    pub fn new(settings: CartesianSettings) -> Self {
        CartesianArm {
            guard: TargetGuard::new(settings.envelope()),
            settings,
            activity: Activity::Waiting,
            target: None,
            measured: None,
            previous: None,
            finished: Vec::new(),
            fault: None,
            on_plate: None,
            progress: 0.0,
            hold_once: None,
            engaged: false,
        }
    }

    /// The settings.
    pub fn settings(&self) -> &CartesianSettings {
        &self.settings
    }

    /// Where a new path starts: the target the arm holds, or where it is.
    fn here(&self) -> Option<[f64; 3]> {
        match self.activity {
            Activity::Stopped | Activity::Waiting => {
                self.measured.map(|m| m.pose_mm).or(self.target)
            }
            _ => self.target.or(self.measured.map(|m| m.pose_mm)),
        }
    }

    /// The legs of a slide from `here`.
    fn slide_legs(&self, here: [f64; 3], s: &SlideOnPlate, depth: f64) -> Vec<Leg> {
        let st = &self.settings;
        let (h, press) = (st.travel_height_mm, -depth);
        let at_start = (here[0] - s.start[0]).hypot(here[1] - s.start[1]) < 0.05
            && (here[2] - press).abs() < 0.05;
        let stroke = Leg {
            to: [s.end[0], s.end[1], press],
            speed: s.speed_mm_s,
            kind: LegKind::Stroke,
        };
        if at_start {
            // Straight on from where the last stroke held: the finger never leaves the plate.
            return vec![stroke];
        }
        let vertical = |to: [f64; 3]| Leg {
            to,
            speed: st.approach_speed_mm_s,
            kind: LegKind::Vertical,
        };
        vec![
            vertical([here[0], here[1], h]),
            Leg {
                to: [s.start[0], s.start[1], h],
                speed: st.travel_speed_mm_s,
                kind: LegKind::Travel,
            },
            vertical([s.start[0], s.start[1], press]),
            stroke,
        ]
    }

    /// Starts a checked command at `now` s; `Some(id)`: slide `id` started.
    pub fn apply(&mut self, command: Checked, now: f64) -> Result<Option<u32>, Refusal> {
        match command {
            Checked::Heartbeat => return Ok(None),
            Checked::Stop => {
                self.stop();
                return Ok(None);
            }
            Checked::Move(_) | Checked::Slide(_) => {}
        }
        if let Some(f) = &self.fault {
            if self.fresh(now).is_none() {
                return Err(Refusal::Faulted(f.to_string()));
            }
        }
        let here = self.fresh(now).and(self.here()).ok_or_else(|| {
            Refusal::Faulted("no pose from the arm: is it publishing?".to_string())
        })?;
        self.fault = None;
        let st = self.settings;
        let (legs, task) = match command {
            Checked::Move(m) => {
                if !(crate::limits::MIN_MOVE_HEIGHT_MM..=MAX_MOVE_HEIGHT_MM).contains(&m.z_mm) {
                    return Err(Refusal::OutOfRange {
                        what: "move height",
                        value: m.z_mm,
                        min: crate::limits::MIN_MOVE_HEIGHT_MM,
                        max: MAX_MOVE_HEIGHT_MM,
                    });
                }
                let legs = vec![
                    Leg {
                        to: [here[0], here[1], m.z_mm],
                        speed: st.approach_speed_mm_s,
                        kind: LegKind::Vertical,
                    },
                    Leg {
                        to: [m.to[0], m.to[1], m.z_mm],
                        speed: m.speed_mm_s,
                        kind: LegKind::Travel,
                    },
                ];
                (legs, Task::Move)
            }
            Checked::Slide(s) => {
                let depth = match s.contact {
                    Contact::DepthMm(d) => f64::from(d),
                    _ => DEFAULT_PRESS_MM,
                };
                let slide = SlideOnPlate {
                    id: s.id,
                    start: s.start,
                    end: s.end,
                    speed_mm_s: s.speed_mm_s,
                };
                (self.slide_legs(here, &slide, depth), Task::Slide(slide))
            }
            Checked::Heartbeat | Checked::Stop => unreachable!("handled above"),
        };
        let id = match &task {
            Task::Slide(s) => Some(s.id),
            _ => None,
        };
        if matches!(self.activity, Activity::Stopped | Activity::Waiting) {
            // A new stream starts from rest where the arm is.
            self.guard.reset();
        }
        self.progress = 0.0;
        self.engaged = false;
        self.activity = Activity::Running {
            path: Path::new(here, &legs, st.max_accel_mm_s2),
            started: now,
            task,
        };
        Ok(id)
    }

    /// Stops at once: the stream ends after one last target where the arm is.
    pub fn stop(&mut self) {
        if !matches!(self.activity, Activity::Stopped) {
            self.activity = Activity::Stopped;
            self.guard.reset();
            self.hold_once = self.measured.map(|m| m.pose_mm).or(self.target);
        }
        self.on_plate = None;
    }

    /// The newest pose, if it is fresh at `now`.
    fn fresh(&self, now: f64) -> Option<Report> {
        self.measured
            .filter(|m| now - m.t_s <= self.settings.stale_after_s)
    }

    /// Takes a pose the arm reported (checked by the DDS side), or a fault it found in one.
    pub fn report(&mut self, report: Result<Report, ArmFault>) {
        match report {
            Ok(r) => {
                self.previous = self.measured;
                self.measured = Some(r);
            }
            Err(f) => self.fail(f),
        }
    }

    /// Faults: the arm stops and says why.
    pub fn fail(&mut self, fault: ArmFault) {
        if self.fault.is_none() {
            tracing::error!("arm fault (code {}): {fault}", fault.code());
        }
        self.fault = Some(fault);
        self.stop();
    }

    /// Advances to `now` s and says what to publish; `reports` is how many poses arrived since
    /// the last tick (a flood check).
    pub fn tick(&mut self, now: f64, reports: usize) -> Publish {
        if reports > self.settings.max_reports_per_tick {
            self.fail(ArmFault::Flood {
                count: reports,
                ms: 0.0,
                limit: self.settings.max_reports_per_tick,
            });
        }
        let streaming = !matches!(self.activity, Activity::Stopped | Activity::Waiting);
        if streaming {
            let since = self.measured.map_or(f64::INFINITY, |m| now - m.t_s);
            if let Some(f) = staleness(since, self.settings.stale_after_s) {
                self.fail(f);
            }
        }
        if let (Some(m), Some(t), true) = (self.measured, self.target, streaming) {
            if let Some(f) = divergence(m.pose_mm, t, self.settings.divergence_mm) {
                self.fail(f);
            }
        }
        if let Some(p) = self.hold_once.take() {
            // Where the arm is, inside the box: hold it there (no speed check: the arm is there).
            let e = self.settings.envelope();
            let inside = (0..3).all(|k| p[k] >= e.min_mm[k] && p[k] <= e.max_mm[k]);
            if inside && p.iter().all(|v| v.is_finite()) {
                self.target = Some(p);
                return Publish::Target(p);
            }
        }
        let Some(next) = self.advance(now) else {
            return Publish::Nothing;
        };
        match self.guard.admit(now, next) {
            Ok(()) => {
                self.target = Some(next);
                Publish::Target(next)
            }
            Err(f) => {
                self.fail(f);
                Publish::Nothing
            }
        }
    }

    /// The target for `now`, moving the state machine on; `None`: the stream is off.
    fn advance(&mut self, now: f64) -> Option<[f64; 3]> {
        match &mut self.activity {
            Activity::Stopped | Activity::Waiting => None,
            Activity::Holding { since, pressed } => {
                if *pressed && now - *since >= self.settings.hold_s {
                    let here = self.target?;
                    let lift = Leg {
                        to: [here[0], here[1], self.settings.travel_height_mm],
                        speed: self.settings.approach_speed_mm_s,
                        kind: LegKind::Vertical,
                    };
                    self.activity = Activity::Running {
                        path: Path::new(here, &[lift], self.settings.max_accel_mm_s2),
                        started: now,
                        task: Task::Lift,
                    };
                    self.on_plate = None;
                }
                self.target
            }
            Activity::Running {
                path,
                started,
                task,
            } => {
                let s = path.at(now - *started);
                let kind = path.kinds().nth(s.leg);
                match task {
                    Task::Slide(slide) => {
                        let on_stroke = kind == Some(LegKind::Stroke);
                        let pressing = on_stroke
                            || (kind == Some(LegKind::Vertical) && s.leg > 0 && s.point[2] < 0.0);
                        self.on_plate = pressing.then_some(*slide);
                        self.progress = if on_stroke { s.fraction } else { 0.0 };
                        self.engaged = on_stroke;
                    }
                    Task::Move | Task::Lift => self.on_plate = None,
                }
                if s.done {
                    let pressed = matches!(task, Task::Slide(_));
                    if let Task::Slide(slide) = task {
                        self.finished.push(slide.id);
                    }
                    self.activity = Activity::Holding {
                        since: now,
                        pressed,
                    };
                }
                Some(s.point)
            }
        }
    }

    /// The mode the link reports.
    pub fn mode(&self) -> Mode {
        match &self.activity {
            Activity::Stopped => Mode::Stopped,
            Activity::Waiting | Activity::Holding { .. } => Mode::Idle,
            Activity::Running { task, .. } => match task {
                Task::Move => Mode::Moving,
                Task::Slide(s) if self.engaged => Mode::Sliding(s.id),
                Task::Slide(_) => Mode::Moving,
                Task::Lift => Mode::Idle,
            },
        }
    }

    /// Whether the arm is moving (the watchdog stops only a moving arm).
    pub fn is_busy(&self) -> bool {
        matches!(self.activity, Activity::Running { .. })
    }

    /// The state the link streams: the newest pose, `time_us` its arrival.
    pub fn state(&self) -> Option<ArmState> {
        let m = self.measured?;
        let velocity = match self.previous {
            Some(p) if m.t_s > p.t_s => {
                [0, 1, 2].map(|k| (m.pose_mm[k] - p.pose_mm[k]) / (m.t_s - p.t_s))
            }
            _ => [0.0; 3],
        };
        Some(ArmState {
            time_us: (m.t_s * 1e6).max(0.0) as u64,
            pose: m.pose_mm,
            velocity,
            mode: self.mode(),
            progress: self.progress,
        })
    }

    /// Slides finished since the last call.
    pub fn take_finished(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.finished)
    }

    /// The fault that stopped the arm, if any (cleared by the next accepted command).
    pub fn fault(&self) -> Option<&ArmFault> {
        self.fault.as_ref()
    }

    /// The slide the finger is pressed on, if any.
    pub fn on_plate(&self) -> Option<SlideOnPlate> {
        self.on_plate
    }

    /// The last published target.
    pub fn target(&self) -> Option<[f64; 3]> {
        self.target
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::{CheckedMove, CheckedSlide};

    const DT: f64 = 0.008;

    fn arm() -> CartesianArm {
        let limits = Limits {
            min_mm: [0.0, 0.0],
            max_mm: [200.0, 100.0],
            max_travel_speed_mm_s: 100.0,
            max_slide_speed_mm_s: 15.56,
        };
        let mut a = CartesianArm::new(CartesianSettings::new(limits));
        a.report(Ok(Report {
            t_s: 0.0,
            pose_mm: [10.0, 10.0, 20.0],
        }));
        a
    }

    fn slide(id: u32, start: [f64; 2], end: [f64; 2]) -> Checked {
        Checked::Slide(CheckedSlide {
            id,
            start,
            end,
            speed_mm_s: 4.0,
            contact: Contact::DepthMm(1.0),
        })
    }

    /// Ticks at 125 Hz from `t` for `secs`, an arm that follows each target exactly one tick
    /// later reporting its pose; returns the published targets with their modes.
    fn run(a: &mut CartesianArm, t: &mut f64, secs: f64) -> Vec<([f64; 3], Mode, f64)> {
        let mut out = Vec::new();
        let end = *t + secs;
        while *t < end {
            *t += DT;
            if let Some(p) = a.target() {
                a.report(Ok(Report {
                    t_s: *t,
                    pose_mm: p,
                }));
            }
            if let Publish::Target(p) = a.tick(*t, 1) {
                out.push((p, a.mode(), a.state().expect("state").progress));
            }
        }
        out
    }

    #[test]
    fn a_slide_travels_presses_strokes_at_its_speed_holds_and_a_slide_back_goes_on_pressed() {
        let mut a = arm();
        // Before any command: idle, streaming nothing.
        assert_eq!((a.mode(), a.tick(0.0, 1)), (Mode::Idle, Publish::Nothing));
        let mut t = 0.0;
        assert_eq!(
            a.apply(slide(3, [50.0, 40.0], [50.0, 56.0]), t),
            Ok(Some(3))
        );
        let (mut first, mut finished) = (Vec::new(), Vec::new());
        while finished.is_empty() && t < 20.0 {
            first.extend(run(&mut a, &mut t, 0.1));
            finished = a.take_finished();
        }
        assert_eq!(finished, vec![3]);
        let stroke: Vec<_> = first.iter().filter(|(p, _, _)| p[2] == -1.0).collect();
        assert!(stroke
            .iter()
            .all(|(p, m, _)| *m == Mode::Sliding(3) || p[1] >= 56.0 - 1e-9));
        // 16 mm at 4 mm/s (plus the 8 ms ramps): about 4 s pressed and moving.
        let moving = stroke.windows(2).filter(|w| w[1].0 != w[0].0).count() as f64 * DT;
        assert!((moving - 4.0).abs() < 0.1, "{moving} s on the stroke");
        let top = first.iter().map(|(p, _, _)| p[2]).fold(f64::MIN, f64::max);
        assert!(top <= 20.0, "the finger rose above where it was: {top}");
        // Held pressed at the end, idle; a slide straight back starts there, still pressed.
        let (end, mode, _) = *first.last().expect("targets");
        assert_eq!((end, mode), ([50.0, 56.0, -1.0], Mode::Idle));
        a.apply(slide(4, [50.0, 56.0], [50.0, 40.0]), t)
            .expect("back");
        let back = run(&mut a, &mut t, 4.5);
        assert!(
            back.iter().all(|(p, _, _)| p[2] == -1.0),
            "lifted on the way back"
        );
        assert_eq!(a.take_finished(), vec![4]);
        let progress: Vec<f64> = back.iter().map(|b| b.2).collect();
        assert!(progress.windows(2).all(|w| w[1] >= w[0]) && progress.contains(&1.0));
        // Left alone, it lifts to the travel height after the hold.
        let after = run(&mut a, &mut t, 3.0);
        assert_eq!(after.last().map(|x| x.0), Some([50.0, 40.0, 5.0]));
        assert_eq!(a.on_plate(), None);
    }

    #[test]
    fn a_stop_ends_the_target_stream_at_once_after_one_target_where_the_arm_is() {
        let mut a = arm();
        let mut t = 0.0;
        let to = Checked::Move(CheckedMove {
            to: [150.0, 80.0],
            z_mm: 20.0,
            speed_mm_s: 50.0,
        });
        a.apply(to, t).expect("move");
        run(&mut a, &mut t, 1.0);
        let here = a.state().expect("state").pose;
        a.apply(Checked::Stop, t).expect("stop");
        assert_eq!(a.mode(), Mode::Stopped);
        assert!(!a.is_busy());
        // One target, where the arm was when told to stop, then nothing.
        let held = run(&mut a, &mut t, 1.0);
        assert_eq!(held.len(), 1, "{held:?}");
        assert_eq!(held[0].0, here);
        // A new command starts from where it is.
        a.apply(to, t).expect("move again");
        assert!(!run(&mut a, &mut t, 0.1).is_empty());
    }

    #[test]
    fn a_quiet_drifting_or_flooding_arm_is_a_fault_that_ends_the_stream() {
        // Quiet: no pose for longer than the limit.
        let mut a = arm();
        a.apply(slide(1, [50.0, 40.0], [50.0, 56.0]), 0.0)
            .expect("slide");
        assert!(matches!(a.tick(0.1, 0), Publish::Target(_)));
        assert!(matches!(a.tick(0.2, 0), Publish::Target(_)));
        let after: Vec<Publish> = (0..3).map(|k| a.tick(0.3 + k as f64 * DT, 0)).collect();
        // The one hold target where the arm last said it was, then nothing.
        assert_eq!(after[0], Publish::Target([10.0, 10.0, 20.0]));
        assert_eq!(after[1..], [Publish::Nothing, Publish::Nothing]);
        assert_eq!(a.fault().map(ArmFault::code), Some(11));
        assert_eq!(a.mode(), Mode::Stopped);
        // A command while the arm is still quiet is refused, naming the fault.
        let e = a
            .apply(slide(2, [50.0, 40.0], [50.0, 56.0]), 0.5)
            .unwrap_err();
        assert!(e.to_string().contains("no pose from the arm"), "{e}");
        // Drifting: the pose 12 mm off its target.
        let mut a = arm();
        a.apply(slide(1, [50.0, 40.0], [50.0, 56.0]), 0.0)
            .expect("slide");
        a.tick(0.01, 1);
        a.report(Ok(Report {
            t_s: 0.02,
            pose_mm: [22.0, 10.0, 20.0],
        }));
        a.tick(0.02, 1);
        assert_eq!(a.fault().map(ArmFault::code), Some(12));
        // Flooding.
        let mut a = arm();
        a.apply(slide(1, [50.0, 40.0], [50.0, 56.0]), 0.0)
            .expect("slide");
        a.tick(0.01, 5000);
        assert_eq!(a.fault().map(ArmFault::code), Some(14));
        assert!(!a.is_busy());
    }

    #[test]
    fn a_path_over_the_limits_is_never_published() {
        // A planted fault: travel set faster than the arm's limit.
        let mut a = arm();
        a.settings.travel_speed_mm_s = 400.0;
        a.apply(slide(1, [150.0, 40.0], [150.0, 56.0]), 0.0)
            .expect("slide");
        let mut t = 0.0;
        let out = run(&mut a, &mut t, 6.0);
        assert_eq!(a.fault().map(ArmFault::code), Some(10), "{:?}", a.fault());
        let fastest = out
            .windows(2)
            .map(|w| {
                let d = (0..3).map(|k| (w[1].0[k] - w[0].0[k]).powi(2)).sum::<f64>();
                d.sqrt() / DT
            })
            .fold(0.0, f64::max);
        assert!(fastest <= 105.0, "{fastest} mm/s published");
    }
}
