//! What a station knows of each robot: the latest of every topic, the verdicts so far, the last
//! minute of tactile samples, and whether the robot is still there. No network here: a
//! [`crate::Station`] feeds it from Zenoh, the operator app feeds it from an in-process mission or
//! a replay through the same [`RobotView::apply`].

use std::collections::{BTreeMap, VecDeque};
use std::time::{Duration, Instant};

use crate::wire::{
    CameraFrame, Detection, Envelope, Feeling, Health, MissionStatus, PassVerdict, Phase,
    PlannedSlides, TactileSample, Telemetry,
};

/// A robot not heard from for this long is shown as lost (its heartbeat runs at ≥ 4 Hz).
pub const LOST_AFTER: Duration = Duration::from_millis(1500);

/// Tactile samples kept per robot: a minute at 400 Hz, times a simulation speed-up of up to 8.
pub const TACTILE_KEPT: usize = 60 * 400 * 8;

/// One robot as the station sees it.
#[derive(Debug, Clone)]
pub struct RobotView {
    /// Its name.
    pub name: String,
    /// Its liveliness token is present (`None`: not known yet).
    pub alive: Option<bool>,
    /// When a sample of it last arrived.
    pub last_heard: Option<Instant>,
    /// Its last heartbeat.
    pub health: Option<Health>,
    /// The current (or last) mission.
    pub mission: Option<MissionStatus>,
    /// The mission's frame.
    pub camera: Option<CameraFrame>,
    /// Its candidates.
    pub detections: Vec<Detection>,
    /// Its plan.
    pub plan: Option<PlannedSlides>,
    /// Judged passes so far, by id.
    pub verdicts: Vec<PassVerdict>,
    /// The running verdict of the pass under way (cleared when its verdict arrives).
    pub feeling: Option<Feeling>,
    /// The latest tactile samples, oldest first.
    pub tactile: VecDeque<TactileSample>,
    /// Tactile samples received in all.
    pub tactile_total: u64,
    /// Samples received in all.
    pub received: u64,
    /// Samples whose sequence number went backwards or repeated (dropped).
    pub out_of_order: u64,
    /// Samples that did not decode (counted by the station).
    pub undecodable: u64,
    /// Delay of the last sample, ms (the robot's send time against this host's clock).
    pub latency_ms: Option<f64>,
    last_seq: u64,
}

impl RobotView {
    /// A robot not heard from yet.
    pub fn new(name: &str) -> Self {
        RobotView {
            name: name.to_string(),
            alive: None,
            last_heard: None,
            health: None,
            mission: None,
            camera: None,
            detections: Vec::new(),
            plan: None,
            verdicts: Vec::new(),
            feeling: None,
            tactile: VecDeque::new(),
            tactile_total: 0,
            received: 0,
            out_of_order: 0,
            undecodable: 0,
            latency_ms: None,
            last_seq: 0,
        }
    }

    /// Takes one sample in. Samples of the state query are applied too (they repeat the latest
    /// of each topic: a repeated sequence number is not counted as out of order).
    pub fn apply(&mut self, env: Envelope, now: Instant) {
        self.received += 1;
        self.last_heard = Some(now);
        self.latency_ms = Some(crate::command::unix_ms() as f64 - env.sent_unix_ms as f64);
        if env.seq < self.last_seq && matches!(env.body, Telemetry::Tactile(_)) {
            // A late tactile chunk would scramble the plot's time axis.
            self.out_of_order += 1;
            return;
        }
        self.last_seq = self.last_seq.max(env.seq);
        self.apply_body(env.body);
    }

    /// Takes one sample's content in.
    pub fn apply_body(&mut self, body: Telemetry) {
        match body {
            Telemetry::Tactile(s) => {
                self.tactile_total += s.len() as u64;
                self.tactile.extend(s);
                while self.tactile.len() > TACTILE_KEPT {
                    self.tactile.pop_front();
                }
            }
            Telemetry::Camera(f) => self.camera = Some(f),
            Telemetry::Detections(d) => self.detections = d,
            Telemetry::Plan(p) => self.plan = Some(p),
            Telemetry::Verdict(v) => {
                if self.feeling.as_ref().is_some_and(|f| f.id <= v.id) {
                    self.feeling = None;
                }
                match self.verdicts.iter_mut().find(|x| x.id == v.id) {
                    Some(x) => *x = v,
                    None => {
                        self.verdicts.push(v);
                        self.verdicts.sort_by_key(|x| x.id);
                    }
                }
            }
            Telemetry::Feeling(f) => {
                // A late running verdict of a pass already judged is not shown again.
                if !self.verdicts.iter().any(|v| v.id >= f.id) {
                    self.feeling = Some(f);
                }
            }
            Telemetry::Health(h) => self.health = Some(h),
            Telemetry::Mission(m) => {
                let new_mission = self.mission.as_ref().is_none_or(|o| o.mission != m.mission);
                if new_mission {
                    self.camera = None;
                    self.detections.clear();
                    self.plan = None;
                    self.verdicts.clear();
                    self.feeling = None;
                    self.tactile.clear();
                }
                self.mission = Some(m);
            }
        }
    }

    /// Whether the robot is lost: its liveliness token went away, or nothing arrived for
    /// [`LOST_AFTER`].
    pub fn is_lost(&self, now: Instant) -> bool {
        self.alive == Some(false)
            || self
                .last_heard
                .is_none_or(|t| now.saturating_duration_since(t) > LOST_AFTER)
    }

    /// The mission's phase, if any.
    pub fn phase(&self) -> Option<&Phase> {
        self.mission.as_ref().map(|m| &m.phase)
    }
}

/// Every robot a station has heard of, by name.
#[derive(Debug, Clone, Default)]
pub struct Fleet {
    robots: BTreeMap<String, RobotView>,
}

impl Fleet {
    /// No robot yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes a sample in (a new robot appears with its first sample).
    pub fn apply(&mut self, env: Envelope, now: Instant) {
        let name = env.robot.clone();
        self.robot_mut(&name).apply(env, now);
    }

    /// A robot's liveliness token appeared or went away.
    pub fn set_alive(&mut self, name: &str, alive: bool) {
        self.robot_mut(name).alive = Some(alive);
    }

    /// A sample of `name` that did not decode.
    pub fn count_undecodable(&mut self, name: &str) {
        self.robot_mut(name).undecodable += 1;
    }

    /// The robot called `name`, created when new.
    pub fn robot_mut(&mut self, name: &str) -> &mut RobotView {
        self.robots
            .entry(name.to_string())
            .or_insert_with(|| RobotView::new(name))
    }

    /// The robot called `name`.
    pub fn robot(&self, name: &str) -> Option<&RobotView> {
        self.robots.get(name)
    }

    /// Every robot, by name.
    pub fn robots(&self) -> impl Iterator<Item = &RobotView> {
        self.robots.values()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::WIRE_VERSION;

    fn env(seq: u64, body: Telemetry) -> Envelope {
        Envelope {
            version: WIRE_VERSION,
            robot: "r1".into(),
            seq,
            sent_unix_ms: crate::command::unix_ms(),
            body,
        }
    }

    fn status(mission: u32, phase: Phase) -> Telemetry {
        Telemetry::Mission(MissionStatus {
            mission,
            mode: "fused".into(),
            scene: "s".into(),
            phase,
            report_json: None,
        })
    }

    #[test]
    fn a_new_mission_clears_the_last_ones_detections_plan_and_verdicts() {
        let mut f = Fleet::new();
        let t = Instant::now();
        f.apply(env(1, status(1, Phase::Starting)), t);
        f.apply(
            env(
                2,
                Telemetry::Tactile(vec![TactileSample {
                    t_s: 0.0,
                    raw: [1, 2, 3, 4],
                }]),
            ),
            t,
        );
        f.apply(
            env(
                3,
                Telemetry::Plan(PlannedSlides {
                    slides: vec![],
                    estimated_s: 1.0,
                }),
            ),
            t,
        );
        f.apply(env(4, status(1, Phase::Finished)), t);
        let r = f.robot("r1").expect("r1");
        assert!(r.plan.is_some());
        assert_eq!(r.tactile.len(), 1);
        f.apply(env(5, status(2, Phase::Starting)), t);
        let r = f.robot("r1").expect("r1");
        assert!(r.plan.is_none() && r.tactile.is_empty());
        assert_eq!(r.received, 5);
    }

    #[test]
    fn a_running_verdict_shows_until_its_pass_is_judged_and_never_after() {
        let mut f = Fleet::new();
        let t = Instant::now();
        let feeling = |id: u32, windows: u64| {
            Telemetry::Feeling(Feeling {
                id,
                class: "crack".into(),
                confidence: 0.7,
                width_mm: Some(5.0),
                windows,
                along_mm: 3.0,
            })
        };
        let verdict = |id: u32| Telemetry::Verdict(crate::wire::example_verdict(id));
        f.apply(env(1, status(1, Phase::Starting)), t);
        f.apply(env(2, feeling(1, 10)), t);
        f.apply(env(3, feeling(1, 20)), t);
        let r = f.robot("r1").expect("r1");
        assert_eq!(r.feeling.as_ref().map(|x| x.windows), Some(20));
        f.apply(env(4, verdict(1)), t);
        assert!(f.robot("r1").expect("r1").feeling.is_none());
        // A running verdict of the judged pass that arrives late is not shown again.
        f.apply(env(5, feeling(1, 30)), t);
        assert!(f.robot("r1").expect("r1").feeling.is_none());
        f.apply(env(6, feeling(2, 10)), t);
        assert_eq!(
            f.robot("r1").expect("r1").feeling.as_ref().map(|x| x.id),
            Some(2)
        );
        // A new mission starts with none.
        f.apply(env(7, status(2, Phase::Starting)), t);
        assert!(f.robot("r1").expect("r1").feeling.is_none());
    }

    #[test]
    fn a_late_tactile_chunk_is_dropped_and_counted() {
        let mut f = Fleet::new();
        let t = Instant::now();
        let chunk = |x: f64| {
            Telemetry::Tactile(vec![TactileSample {
                t_s: x,
                raw: [0; 4],
            }])
        };
        f.apply(env(2, chunk(2.0)), t);
        f.apply(env(1, chunk(1.0)), t);
        let r = f.robot("r1").expect("r1");
        assert_eq!(r.tactile.len(), 1);
        assert_eq!(r.out_of_order, 1);
    }

    #[test]
    fn silence_or_a_lost_token_means_lost() {
        let mut f = Fleet::new();
        let t = Instant::now();
        f.apply(env(1, status(1, Phase::Idle)), t);
        assert!(!f.robot("r1").expect("r1").is_lost(t));
        assert!(f
            .robot("r1")
            .expect("r1")
            .is_lost(t + LOST_AFTER + Duration::from_millis(1)));
        f.set_alive("r1", false);
        assert!(f.robot("r1").expect("r1").is_lost(t));
    }
}
