//! The ROS 2 topics crackbot writes, their message types and the QoS their publishers offer.

use crate::msgs::MsgType;

/// How a topic is delivered (the publisher's offered QoS).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Qos {
    /// Reliable (`true`) or best effort.
    pub reliable: bool,
    /// Transient local (`true`: a late subscriber gets the last `depth` messages) or volatile.
    pub transient_local: bool,
    /// Keep-last depth.
    pub depth: u32,
}

/// The 400 Hz stream: best effort, volatile (a lost sample is not resent; a late one is useless).
pub const STREAM: Qos = Qos {
    reliable: false,
    transient_local: false,
    depth: 400,
};
/// Events: reliable, volatile.
pub const EVENTS: Qos = Qos {
    reliable: true,
    transient_local: false,
    depth: 100,
};
/// What a late subscriber must get: reliable, transient local.
pub const LATCHED: Qos = Qos {
    reliable: true,
    transient_local: true,
    depth: 1,
};
/// Every verdict of a mission to a late subscriber: reliable, transient local, deep.
pub const LATCHED_ALL: Qos = Qos {
    reliable: true,
    transient_local: true,
    depth: 1000,
};

/// A topic crackbot publishes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RosTopic {
    /// The camera frame the mission looked at.
    Image,
    /// The finger's samples, 400 Hz.
    Tactile,
    /// The samples of each recorded stroke.
    StrokeSamples,
    /// The arm's pose over the surface.
    ArmPose,
    /// The finger's frame in the surface's.
    Tf,
    /// Each pass, when it ends.
    Strokes,
    /// Each pass's verdict.
    Verdicts,
    /// The running verdict of the pass under way.
    Feeling,
    /// The stream's and link's counters.
    Health,
    /// The mission's stage.
    Status,
    /// The mission's report.
    Report,
    /// The log.
    Rosout,
}

impl RosTopic {
    /// Every one, in the order a bag creates them.
    pub const ALL: [RosTopic; 12] = [
        RosTopic::Image,
        RosTopic::Tactile,
        RosTopic::StrokeSamples,
        RosTopic::ArmPose,
        RosTopic::Tf,
        RosTopic::Strokes,
        RosTopic::Verdicts,
        RosTopic::Feeling,
        RosTopic::Health,
        RosTopic::Status,
        RosTopic::Report,
        RosTopic::Rosout,
    ];

    /// Its ROS 2 name.
    pub fn name(self) -> &'static str {
        match self {
            RosTopic::Image => "/crackbot/camera/image/compressed",
            RosTopic::Tactile => "/crackbot/tactile",
            RosTopic::StrokeSamples => "/crackbot/stroke/samples",
            RosTopic::ArmPose => "/crackbot/arm/pose",
            RosTopic::Tf => "/tf",
            RosTopic::Strokes => "/crackbot/strokes",
            RosTopic::Verdicts => "/crackbot/verdicts",
            RosTopic::Feeling => "/crackbot/feeling",
            RosTopic::Health => "/crackbot/health",
            RosTopic::Status => "/crackbot/mission/status",
            RosTopic::Report => "/crackbot/mission/report",
            RosTopic::Rosout => "/rosout",
        }
    }

    /// Its message type.
    pub fn msg_type(self) -> MsgType {
        match self {
            RosTopic::Image => MsgType::CompressedImage,
            RosTopic::Tactile | RosTopic::StrokeSamples => MsgType::TactileSample,
            RosTopic::ArmPose => MsgType::PoseStamped,
            RosTopic::Tf => MsgType::TfMessage,
            RosTopic::Strokes => MsgType::Stroke,
            RosTopic::Verdicts | RosTopic::Feeling => MsgType::Verdict,
            RosTopic::Health => MsgType::StreamHealth,
            RosTopic::Status => MsgType::MissionStatus,
            RosTopic::Report => MsgType::MissionReport,
            RosTopic::Rosout => MsgType::Log,
        }
    }

    /// The QoS its publisher offers.
    pub fn qos(self) -> Qos {
        match self {
            RosTopic::Tactile | RosTopic::ArmPose | RosTopic::Tf | RosTopic::Feeling => STREAM,
            RosTopic::StrokeSamples | RosTopic::Health | RosTopic::Rosout => EVENTS,
            RosTopic::Image | RosTopic::Status | RosTopic::Report => LATCHED,
            RosTopic::Strokes | RosTopic::Verdicts => LATCHED_ALL,
        }
    }
}

/// `qos` as rosbag2's metadata writes an offered profile (the YAML of metadata version 5–8:
/// history 1 keep last, reliability 1 reliable / 2 best effort, durability 1 transient local /
/// 2 volatile, the rest at their defaults), as a one-element list.
pub fn qos_yaml(qos: Qos) -> String {
    let forever = "\n    sec: 2147483647\n    nsec: 4294967295";
    format!(
        "- history: 1\n  depth: {}\n  reliability: {}\n  durability: {}\n  deadline:{forever}\n  lifespan:{forever}\n  liveliness: 1\n  liveliness_lease_duration:{forever}\n  avoid_ros_namespace_conventions: false",
        qos.depth,
        if qos.reliable { 1 } else { 2 },
        if qos.transient_local { 1 } else { 2 },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_topic_is_named_once_and_latched_ones_are_reliable() {
        let mut names: Vec<&str> = RosTopic::ALL.iter().map(|t| t.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), RosTopic::ALL.len());
        for t in RosTopic::ALL {
            assert!(!t.qos().transient_local || t.qos().reliable, "{t:?}");
        }
        assert!(!RosTopic::Tactile.qos().reliable);
        assert!(RosTopic::Report.qos().transient_local);
        assert!(qos_yaml(STREAM).contains("reliability: 2\n  durability: 2"));
    }
}
