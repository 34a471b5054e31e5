//! The ROS 2 arm: crackbot's targets out as `geometry_msgs/msg/PoseStamped`, the tool's pose
//! back from a pose topic or `/tf`, over DDS with ROS 2's names (spec:
//! `crates/controller/docs/ros2.md`).
//!
//! * [`config`]: the ROS 2 configuration file (topics, frames, rates, tolerances).
//! * [`site`]: the arm's limits and the registered surface, from the site file.
//! * `msgs` (feature `ros2`): the ROS 2 messages as serde structs (`crackbot_rosbag::msgs`).
//! * `dds` and [`Ros2Arm`] (feature `ros2`): the DDS node (ros2-client on RustDDS, no ROS
//!   installation) driving [`crate::motion::cartesian::CartesianArm`] as an [`crate::Arm`];
//!   `touch`: guarded touches for registering the plate.

pub mod config;
#[cfg(feature = "ros2")]
mod dds;
/// The ROS 2 messages, shared with the mission's bags and live topics (`crackbot-rosbag`).
#[cfg(feature = "ros2")]
pub use crackbot_rosbag::msgs;
pub mod site;
#[cfg(feature = "ros2")]
mod touch;

#[cfg(feature = "ros2")]
pub use dds::{Ros2Arm, Ros2Error};
#[cfg(feature = "ros2")]
pub use touch::guarded_touches;
