//! The DDS node of the ROS 2 arm and the arm itself ([`Ros2Arm`]): a thread that, at the
//! configured rate, takes the poses (and wrenches) the arm published, checks them into the
//! surface frame, advances the [`CartesianArm`] and publishes its target in the base frame.
//! The link side talks to the same [`CartesianArm`] through [`Ros2Arm`]'s [`Arm`] methods.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use ros2_client::qos::WhenFull;
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile, Subscription,
};

use super::config::{Ros2Config, Source};
use super::msgs::{Header, Point, Pose, PoseStamped, Quaternion, TfMessage, Time, WrenchStamped};
use crate::arm::{Arm, ArmState};
use crate::command::Checked;
use crate::limits::{Limits, Refusal};
use crate::motion::cartesian::{CartesianArm, Publish, Report, SlideOnPlate};
use crate::motion::frame::SurfaceFrame;
use crate::motion::guard::{check_report, ArmFault};

/// The ROS 2 arm could not start.
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// A name is not a valid ROS 2 name.
    #[error("{what} {name:?} is not a valid ROS 2 name: {why}")]
    Name {
        /// Which.
        what: &'static str,
        /// The name.
        name: String,
        /// Why.
        why: String,
    },
    /// DDS refused to create something.
    #[error("DDS: could not create the {what}: {why}")]
    Create {
        /// What.
        what: &'static str,
        /// Why.
        why: String,
    },
    /// The node thread could not start.
    #[error("the ROS 2 node's thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The arm faulted (a broken or silent pose stream).
    #[error("the arm: {0}")]
    Arm(#[source] ArmFault),
    /// A guarded touch failed.
    #[error("guarded touch: {0}")]
    Touch(String),
    /// A target could not be published.
    #[error("DDS: publishing the target: {0}")]
    Publish(String),
}

/// What the link side and the node share.
#[derive(Debug)]
struct Core {
    arm: CartesianArm,
}

type Shared = Arc<Mutex<Core>>;

fn lock(s: &Shared) -> MutexGuard<'_, Core> {
    s.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// A ROS 2 arm over DDS.
#[derive(Debug)]
pub struct Ros2Arm {
    core: Shared,
    started: Instant,
    stop: Arc<AtomicBool>,
    node: Option<JoinHandle<()>>,
}

/// Splits `/a/b/c` into the namespace `/a/b` and the base name `c`.
fn topic_name(what: &'static str, topic: &str) -> Result<Name, Ros2Error> {
    let bad = |why: String| Ros2Error::Name {
        what,
        name: topic.to_string(),
        why,
    };
    let full = if topic.starts_with('/') {
        topic.to_string()
    } else {
        format!("/{topic}")
    };
    let (ns, base) = full.rsplit_once('/').ok_or_else(|| bad("no name".into()))?;
    Name::new(if ns.is_empty() { "/" } else { ns }, base).map_err(|e| bad(format!("{e:?}")))
}

fn create<T, E: std::fmt::Debug>(what: &'static str, r: Result<T, E>) -> Result<T, Ros2Error> {
    r.map_err(|e| Ros2Error::Create {
        what,
        why: format!("{e:?}"),
    })
}

/// The node's DDS entities.
pub(super) struct Endpoints {
    /// Keeps the node (and its participant) alive.
    _node: Node,
    target: Publisher<PoseStamped>,
    pose: Option<Subscription<PoseStamped>>,
    tf: Option<Subscription<TfMessage>>,
    wrench: Option<Subscription<WrenchStamped>>,
}

pub(super) fn endpoints(config: &Ros2Config) -> Result<Endpoints, Ros2Error> {
    let context = create(
        "DDS participant",
        Context::with_options(ContextOptions::new().domain_id(config.dds.domain_id)),
    )?;
    let name = NodeName::new("/", &config.dds.node).map_err(|e| Ros2Error::Name {
        what: "dds.node",
        name: config.dds.node.clone(),
        why: format!("{e:?}"),
    })?;
    let mut node = create(
        "node",
        context.new_node(name, NodeOptions::new().enable_rosout(false)),
    )?;
    // Reliable, keep last 1, never blocking the tick: matches reliable and best-effort readers.
    let target_qos = QosProfile::publisher_default().reliability_reliable(WhenFull::Fail);
    // Best effort, keep last: matches reliable and best-effort writers.
    let reader_qos = QosProfile::subscription_default()
        .history(ros2_client::qos::History::KeepLast { depth: 64 });
    let topic = create(
        "target topic",
        node.create_topic(
            &topic_name("target.topic", &config.target.topic)?,
            MessageTypeName::new("geometry_msgs", "PoseStamped"),
            &target_qos,
        ),
    )?;
    let target = create("target publisher", node.create_publisher(&topic, None))?;
    let (mut pose, mut tf) = (None, None);
    match config.pose.source {
        Source::Pose => {
            let t = create(
                "pose topic",
                node.create_topic(
                    &topic_name("pose.topic", &config.pose.topic)?,
                    MessageTypeName::new("geometry_msgs", "PoseStamped"),
                    &reader_qos,
                ),
            )?;
            pose = Some(create(
                "pose subscription",
                node.create_subscription(&t, None),
            )?);
        }
        Source::Tf => {
            let t = create(
                "tf topic",
                node.create_topic(
                    &topic_name("tf", "/tf")?,
                    MessageTypeName::new("tf2_msgs", "TFMessage"),
                    &reader_qos,
                ),
            )?;
            tf = Some(create(
                "tf subscription",
                node.create_subscription(&t, None),
            )?);
        }
    }
    let wrench = if config.wrench.topic.is_empty() {
        None
    } else {
        let t = create(
            "wrench topic",
            node.create_topic(
                &topic_name("wrench.topic", &config.wrench.topic)?,
                MessageTypeName::new("geometry_msgs", "WrenchStamped"),
                &reader_qos,
            ),
        )?;
        Some(create(
            "wrench subscription",
            node.create_subscription(&t, None),
        )?)
    };
    Ok(Endpoints {
        _node: node,
        target,
        pose,
        tf,
        wrench,
    })
}

/// Most messages taken from one subscription per tick (a flood is found by counting, and the
/// tick must end).
const MAX_TAKEN: usize = 10_000;

/// Poses received since the last tick: how many, and the newest checked one (or the first
/// fault found).
pub(super) fn take_poses(
    e: &Endpoints,
    config: &Ros2Config,
    frame: &SurfaceFrame,
) -> (usize, Option<Result<[f64; 3], ArmFault>>) {
    let base = &config.target.frame;
    let mut count = 0;
    let mut newest: Option<Result<[f64; 3], ArmFault>> = None;
    let mut note = |frame_id: &str, p: Point| {
        if matches!(newest, Some(Err(_))) {
            return;
        }
        let mm = frame.to_surface([p.x, p.y, p.z]);
        newest = Some(check_report(frame_id, base, mm).map(|()| mm));
    };
    if let Some(s) = &e.pose {
        while count < MAX_TAKEN {
            match s.take() {
                Ok(Some((m, _))) => {
                    count += 1;
                    note(&m.header.frame_id, m.pose.position);
                }
                Ok(None) => break,
                Err(err) => {
                    tracing::warn!("a pose message could not be read: {err:?}");
                    break;
                }
            }
        }
    }
    if let Some(s) = &e.tf {
        while count < MAX_TAKEN {
            match s.take() {
                Ok(Some((m, _))) => {
                    // Every /tf message counts towards a flood; only our tool's transform is
                    // a pose.
                    count += 1;
                    for t in m
                        .transforms
                        .iter()
                        .filter(|t| t.child_frame_id == config.pose.tool_frame)
                    {
                        note(&t.header.frame_id, t.transform.translation);
                    }
                }
                Ok(None) => break,
                Err(err) => {
                    tracing::warn!("a /tf message could not be read: {err:?}");
                    break;
                }
            }
        }
    }
    (count, newest)
}

/// The largest contact force among the wrenches received since the last tick, N.
pub(super) fn take_force(e: &Endpoints) -> Option<f64> {
    let s = e.wrench.as_ref()?;
    let mut most: Option<f64> = None;
    for _ in 0..MAX_TAKEN {
        match s.take() {
            Ok(Some((m, _))) => {
                let f = m.wrench.force;
                let n = (f.x * f.x + f.y * f.y + f.z * f.z).sqrt();
                // NaN counts as over any limit.
                let n = if n.is_finite() { n } else { f64::INFINITY };
                most = Some(most.map_or(n, |x: f64| x.max(n)));
            }
            _ => break,
        }
    }
    most
}

/// Publishes one target (mm in the surface frame `frame`).
pub(super) fn publish_target(
    e: &Endpoints,
    config: &Ros2Config,
    frame: &SurfaceFrame,
    p_mm: [f64; 3],
) -> Result<(), Ros2Error> {
    e.target
        .publish(target_message(p_mm, config, frame))
        .map_err(|err| Ros2Error::Publish(format!("{err:?}")))
}

fn target_message(p_mm: [f64; 3], config: &Ros2Config, frame: &SurfaceFrame) -> PoseStamped {
    let b = frame.to_base(p_mm);
    let q = frame.tool_in_base();
    PoseStamped {
        header: Header {
            stamp: Time::now(),
            frame_id: config.target.frame.clone(),
        },
        pose: Pose {
            position: Point {
                x: b[0],
                y: b[1],
                z: b[2],
            },
            orientation: Quaternion {
                x: q[0],
                y: q[1],
                z: q[2],
                w: q[3],
            },
        },
    }
}

/// How often the node takes the arm's poses, s: between targets too, so that a pose is timed
/// within a millisecond of its arrival (the link's states and the simulated finger use it).
const LISTEN_S: f64 = 0.001;

/// Takes what arrived: the newest pose (or a fault in one) and the contact force to the arm.
/// How many poses came.
fn listen(
    e: &Endpoints,
    core: &Shared,
    config: &Ros2Config,
    frame: &SurfaceFrame,
    now: f64,
) -> usize {
    let (count, newest) = take_poses(e, config, frame);
    let force = take_force(e);
    let mut c = lock(core);
    match newest {
        Some(Ok(p)) => c.arm.report(Ok(Report {
            t_s: now,
            pose_mm: p,
        })),
        Some(Err(f)) => c.arm.report(Err(f)),
        None => {}
    }
    if let Some(n) = force.filter(|n| *n > config.wrench.max_force_n) {
        c.arm.fail(ArmFault::OverForce {
            n,
            limit_n: config.wrench.max_force_n,
        });
    }
    count
}

/// One period of the node: the state machine on (`reports` poses came since the last), the
/// target out.
fn tick(
    e: &Endpoints,
    core: &Shared,
    config: &Ros2Config,
    frame: &SurfaceFrame,
    now: f64,
    reports: usize,
) {
    let publish = lock(core).arm.tick(now, reports);
    if let Publish::Target(p) = publish {
        if let Err(err) = publish_target(e, config, frame, p) {
            lock(core).arm.fail(ArmFault::Dds(err.to_string()));
        }
    }
}

/// The node's loop: poses taken every millisecond, a target every period.
fn run_node(
    e: &Endpoints,
    core: &Shared,
    config: &Ros2Config,
    frame: &SurfaceFrame,
    started: Instant,
    stop: &AtomicBool,
) {
    let period = 1.0 / config.target.rate_hz;
    let mut next = 0.0;
    let mut reports = 0;
    while !stop.load(Ordering::Relaxed) {
        let now = started.elapsed().as_secs_f64();
        reports += listen(e, core, config, frame, now);
        if now >= next {
            tick(e, core, config, frame, now, reports);
            reports = 0;
            // A few periods late (a busy host), the stream catches up; further, it starts afresh.
            next += period;
            if next + 3.0 * period < now {
                next = now + period;
            }
        }
        let wait = (next - started.elapsed().as_secs_f64()).clamp(0.0, LISTEN_S);
        std::thread::sleep(Duration::from_secs_f64(wait));
    }
}

impl Ros2Arm {
    /// Joins the DDS domain and starts the node's thread: targets at `config.target.rate_hz`
    /// once a command arrives, poses taken every period.
    pub fn spawn(
        config: Ros2Config,
        limits: Limits,
        surface: SurfaceFrame,
    ) -> Result<Ros2Arm, Ros2Error> {
        let core: Shared = Arc::new(Mutex::new(Core {
            arm: CartesianArm::new(config.cartesian(limits)),
        }));
        let endpoints = endpoints(&config)?;
        let started = Instant::now();
        let stop = Arc::new(AtomicBool::new(false));
        let node = {
            let (core, stop) = (core.clone(), stop.clone());
            std::thread::Builder::new()
                .name("ros2 arm".into())
                .spawn(move || run_node(&endpoints, &core, &config, &surface, started, &stop))
                .map_err(Ros2Error::Thread)?
        };
        Ok(Ros2Arm {
            core,
            started,
            stop,
            node: Some(node),
        })
    }

    fn now(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Where the arm is and the slide it presses along, for a simulated finger following it.
    pub fn follower(&self) -> impl FnMut() -> Option<([f64; 3], Option<SlideOnPlate>)> + Send {
        let core = self.core.clone();
        move || {
            let c = lock(&core);
            c.arm.state().map(|s| (s.pose, c.arm.on_plate()))
        }
    }
}

impl Arm for Ros2Arm {
    fn limits(&self) -> Limits {
        lock(&self.core).arm.settings().limits
    }

    fn now_us(&self) -> u64 {
        (self.now() * 1e6) as u64
    }

    fn apply(&mut self, command: Checked) -> Result<Option<u32>, Refusal> {
        let now = self.now();
        lock(&self.core).arm.apply(command, now)
    }

    fn stop(&mut self) {
        lock(&self.core).arm.stop();
    }

    fn is_busy(&self) -> bool {
        lock(&self.core).arm.is_busy()
    }

    fn state(&self) -> Option<ArmState> {
        lock(&self.core).arm.state()
    }

    fn take_finished(&mut self) -> Vec<u32> {
        lock(&self.core).arm.take_finished()
    }

    fn fault(&self) -> Option<(u16, String)> {
        lock(&self.core)
            .arm
            .fault()
            .map(|f| (f.code(), f.to_string()))
    }
}

impl Drop for Ros2Arm {
    fn drop(&mut self) {
        lock(&self.core).arm.stop();
        // One more period publishes the stop's hold target.
        std::thread::sleep(Duration::from_millis(20));
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.node.take() {
            let _ = t.join();
        }
    }
}
