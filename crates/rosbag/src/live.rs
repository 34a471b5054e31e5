//! The same messages published live on ROS 2 topics over DDS (feature `live`: `ros2-client` on
//! RustDDS, no ROS installation), each topic with the QoS [`RosTopic::qos`] gives it.

use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher,
    QosProfile,
};
use serde::Serialize;

use crate::message::RosMessage;
use crate::msgs::{
    CompressedImage, MissionReport, MissionStatus, PoseStamped, RosLog, StreamHealth, Stroke,
    TactileSample, TfMessage, Verdict,
};
use crate::topics::{Qos, RosTopic};

/// Why the live node could not start or publish.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// DDS refused to create something.
    #[error("DDS: could not create {what}: {why}")]
    Create {
        /// What.
        what: String,
        /// Why.
        why: String,
    },
    /// A message could not be published.
    #[error("DDS: publishing on {topic}: {why}")]
    Publish {
        /// The topic.
        topic: &'static str,
        /// Why.
        why: String,
    },
}

/// The live node: one publisher per topic.
pub struct LiveRos2 {
    _node: Node,
    image: Publisher<CompressedImage>,
    tactile: Publisher<TactileSample>,
    stroke_samples: Publisher<TactileSample>,
    arm_pose: Publisher<PoseStamped>,
    tf: Publisher<TfMessage>,
    strokes: Publisher<Stroke>,
    verdicts: Publisher<Verdict>,
    feeling: Publisher<Verdict>,
    health: Publisher<StreamHealth>,
    status: Publisher<MissionStatus>,
    report: Publisher<MissionReport>,
    rosout: Publisher<RosLog>,
}

impl std::fmt::Debug for LiveRos2 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LiveRos2")
    }
}

fn profile(q: Qos) -> QosProfile {
    let p = QosProfile::publisher_default().history(History::KeepLast {
        depth: q.depth as usize,
    });
    let p = if q.reliable {
        p.reliability_reliable(WhenFull::DEFAULT)
    } else {
        p.reliability_best_effort()
    };
    p.durability(if q.transient_local {
        Durability::TransientLocal
    } else {
        Durability::Volatile
    })
}

fn create<T, E: std::fmt::Debug>(what: impl Into<String>, r: Result<T, E>) -> Result<T, LiveError> {
    r.map_err(|e| LiveError::Create {
        what: what.into(),
        why: format!("{e:?}"),
    })
}

fn publisher<M: Serialize>(node: &mut Node, t: RosTopic) -> Result<Publisher<M>, LiveError> {
    let full = t.name();
    let (ns, base) = full.rsplit_once('/').unwrap_or(("", full));
    let name = create(
        format!("the name {full}"),
        Name::new(if ns.is_empty() { "/" } else { ns }, base),
    )?;
    let ty = t.msg_type().name();
    let (pkg, rest) = ty.split_once("/msg/").unwrap_or(("", &ty));
    let topic = create(
        format!("the topic {full}"),
        node.create_topic(&name, MessageTypeName::new(pkg, rest), &profile(t.qos())),
    )?;
    create(
        format!("the publisher of {full}"),
        node.create_publisher(&topic, None),
    )
}

impl LiveRos2 {
    /// A node named `node` on DDS domain `domain`, publishing every topic of [`RosTopic::ALL`].
    pub fn open(domain: u16, node: &str) -> Result<Self, LiveError> {
        let context = create(
            "the DDS participant",
            Context::with_options(ContextOptions::new().domain_id(domain)),
        )?;
        let name = create(format!("the node name {node}"), NodeName::new("/", node))?;
        let mut n = create(
            "the node",
            context.new_node(name, NodeOptions::new().enable_rosout(false)),
        )?;
        Ok(LiveRos2 {
            image: publisher(&mut n, RosTopic::Image)?,
            tactile: publisher(&mut n, RosTopic::Tactile)?,
            stroke_samples: publisher(&mut n, RosTopic::StrokeSamples)?,
            arm_pose: publisher(&mut n, RosTopic::ArmPose)?,
            tf: publisher(&mut n, RosTopic::Tf)?,
            strokes: publisher(&mut n, RosTopic::Strokes)?,
            verdicts: publisher(&mut n, RosTopic::Verdicts)?,
            feeling: publisher(&mut n, RosTopic::Feeling)?,
            health: publisher(&mut n, RosTopic::Health)?,
            status: publisher(&mut n, RosTopic::Status)?,
            report: publisher(&mut n, RosTopic::Report)?,
            rosout: publisher(&mut n, RosTopic::Rosout)?,
            _node: n,
        })
    }

    /// Publishes `msg` on its topic.
    pub fn publish(&self, msg: RosMessage) -> Result<(), LiveError> {
        let topic = msg.topic().name();
        let r = match msg {
            RosMessage::Image(m) => self.image.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Tactile(m) => self.tactile.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::StrokeSample(m) => {
                self.stroke_samples.publish(m).map_err(|e| format!("{e:?}"))
            }
            RosMessage::ArmPose(m) => self.arm_pose.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Tf(m) => self.tf.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Stroke(m) => self.strokes.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Verdict(m) => self.verdicts.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Feeling(m) => self.feeling.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Health(m) => self.health.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Status(m) => self.status.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Report(m) => self.report.publish(m).map_err(|e| format!("{e:?}")),
            RosMessage::Log(m) => self.rosout.publish(m).map_err(|e| format!("{e:?}")),
        };
        r.map_err(|why| LiveError::Publish { topic, why })
    }
}
