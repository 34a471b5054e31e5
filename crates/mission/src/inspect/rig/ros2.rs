//! The mission's log live on ROS 2 topics over DDS (feature `ros2`): every message the log
//! writes, turned into its ROS 2 messages (`crackbot_rosbag::ros_messages`, the same as a bag's)
//! and published with each topic's QoS. A message that cannot be published is counted and
//! warned about once; the mission goes on.

use crackbot_mcap::{LoggedMessage, Payload};
use crackbot_rosbag::{ros_messages, LiveRos2};

use crate::MissionError;

/// The node's name.
pub const NODE: &str = "crackbot";
/// How long the node stays after the mission's report, for reliable readers to get it.
pub const LINGER: std::time::Duration = std::time::Duration::from_secs(1);

/// The live node and what it failed to publish.
pub(crate) struct Ros2Tap {
    node: LiveRos2,
    failed: u64,
}

impl Ros2Tap {
    /// A node on DDS domain `domain`.
    pub(crate) fn open(domain: u16) -> Result<Self, MissionError> {
        let node = LiveRos2::open(domain, NODE).map_err(|e| MissionError::Refused {
            what: format!("the ROS 2 node on DDS domain {domain}"),
            reason: e.to_string(),
        })?;
        Ok(Ros2Tap { node, failed: 0 })
    }

    /// Publishes what the log wrote on `topic` at `log_time_ns`.
    pub(crate) fn tap(&mut self, topic: &str, log_time_ns: u64, payload: Payload) {
        let m = LoggedMessage {
            topic: topic.to_string(),
            log_time_ns,
            payload,
        };
        let published = ros_messages(&m)
            .map_err(|e| e.to_string())
            .and_then(|msgs| {
                msgs.into_iter()
                    .try_for_each(|r| self.node.publish(r))
                    .map_err(|e| e.to_string())
            });
        if let Err(e) = published {
            if self.failed == 0 {
                tracing::warn!("ROS 2 live topics: {e} (further failures are counted)");
            }
            self.failed += 1;
        }
    }

    /// Messages that could not be published.
    pub(crate) fn failed(&self) -> u64 {
        self.failed
    }
}
