//! A mission's log as a ROS 2 bag, so ROS 2 users replay a mission with `ros2 bag play` into
//! RViz, Foxglove or their own nodes.
//!
//! rosbag2 plays only CDR-encoded messages whose definitions the bag carries; crackbot's
//! `mission.mcap` holds Foxglove protobuf and JSON. This crate turns the log, as
//! `crackbot_mcap::read_log` decodes it, into ROS 2 messages ([`convert`]: pure, no files):
//! crackbot's own (`ros/crackbot_msgs`, the interface package a ROS 2 workspace builds) where
//! nothing standard fits, standard ones (`sensor_msgs/CompressedImage`, `geometry_msgs/PoseStamped`,
//! `tf2_msgs/TFMessage`, `rcl_interfaces/Log`) where one does; and writes them as rosbag2 writes
//! a bag ([`write_bag`]: the MCAP storage, `ros2msg` schemas, `cdr` channels with their QoS, and
//! `metadata.yaml`). The topics and their QoS are in [`RosTopic`]; the format is specified in
//! `crates/rosbag/docs/ros2.md`. Feature `live`: the same messages published on ROS 2 topics over
//! DDS while a mission runs (`LiveRos2`, ros2-client).

mod convert;
mod error;
#[cfg(feature = "live")]
mod live;
mod message;
pub mod msgs;
mod topics;
mod write;

pub use convert::{
    convert, convert_message, ros_messages, BagMessage, CAMERA_FRAME, FINGER_FRAME, SURFACE_FRAME,
};
pub use error::RosbagError;
#[cfg(feature = "live")]
pub use live::{LiveError, LiveRos2};
pub use message::RosMessage;
pub use topics::{qos_yaml, Qos, RosTopic, EVENTS, LATCHED, LATCHED_ALL, STREAM};
pub use write::{metadata_yaml, write_bag, BagSummary, METADATA_VERSION};

use std::path::Path;

/// Reads the mission log `mcap` and writes it as a ROS 2 bag in `dir`.
pub fn log_to_bag(mcap: &Path, dir: &Path) -> Result<BagSummary, RosbagError> {
    let log = crackbot_mcap::read_log(mcap)?;
    let messages = convert(&log)?;
    write_bag(dir, &messages)
}
