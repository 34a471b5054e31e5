//! One ROS 2 message of any type crackbot publishes, with its topic: what the bag encodes and
//! the live node publishes.

use serde::Serialize;

use crate::msgs::{
    to_cdr, CompressedImage, MissionReport, MissionStatus, PoseStamped, RosLog, StreamHealth,
    Stroke, TactileSample, TfMessage, Verdict,
};
use crate::topics::RosTopic;

/// A message and, by its variant, its topic.
#[derive(Debug, Clone, PartialEq)]
pub enum RosMessage {
    /// On [`RosTopic::Image`].
    Image(CompressedImage),
    /// On [`RosTopic::Tactile`].
    Tactile(TactileSample),
    /// On [`RosTopic::StrokeSamples`].
    StrokeSample(TactileSample),
    /// On [`RosTopic::ArmPose`].
    ArmPose(PoseStamped),
    /// On [`RosTopic::Tf`].
    Tf(TfMessage),
    /// On [`RosTopic::Strokes`].
    Stroke(Stroke),
    /// On [`RosTopic::Verdicts`].
    Verdict(Verdict),
    /// On [`RosTopic::Feeling`].
    Feeling(Verdict),
    /// On [`RosTopic::Health`].
    Health(StreamHealth),
    /// On [`RosTopic::Status`].
    Status(MissionStatus),
    /// On [`RosTopic::Report`].
    Report(MissionReport),
    /// On [`RosTopic::Rosout`].
    Log(RosLog),
}

impl RosMessage {
    /// Its topic.
    pub fn topic(&self) -> RosTopic {
        match self {
            RosMessage::Image(_) => RosTopic::Image,
            RosMessage::Tactile(_) => RosTopic::Tactile,
            RosMessage::StrokeSample(_) => RosTopic::StrokeSamples,
            RosMessage::ArmPose(_) => RosTopic::ArmPose,
            RosMessage::Tf(_) => RosTopic::Tf,
            RosMessage::Stroke(_) => RosTopic::Strokes,
            RosMessage::Verdict(_) => RosTopic::Verdicts,
            RosMessage::Feeling(_) => RosTopic::Feeling,
            RosMessage::Health(_) => RosTopic::Health,
            RosMessage::Status(_) => RosTopic::Status,
            RosMessage::Report(_) => RosTopic::Report,
            RosMessage::Log(_) => RosTopic::Rosout,
        }
    }

    /// Its CDR bytes as a bag stores them.
    pub fn to_cdr(&self) -> Result<Vec<u8>, cdr_encoding::Error> {
        fn cdr<T: Serialize>(m: &T) -> Result<Vec<u8>, cdr_encoding::Error> {
            to_cdr(m)
        }
        match self {
            RosMessage::Image(m) => cdr(m),
            RosMessage::Tactile(m) | RosMessage::StrokeSample(m) => cdr(m),
            RosMessage::ArmPose(m) => cdr(m),
            RosMessage::Tf(m) => cdr(m),
            RosMessage::Stroke(m) => cdr(m),
            RosMessage::Verdict(m) | RosMessage::Feeling(m) => cdr(m),
            RosMessage::Health(m) => cdr(m),
            RosMessage::Status(m) => cdr(m),
            RosMessage::Report(m) => cdr(m),
            RosMessage::Log(m) => cdr(m),
        }
    }
}
