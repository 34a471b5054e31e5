//! The ROS 2 arm's configuration file (TOML): topics, frames, rates and what the arm side
//! tolerates. Every key has a default (`crackbot-controller --arm ros2 --print-ros2-config`
//! prints them); the spec is `crates/controller/docs/ros2.md`.
//!
//! ```toml
//! [dds]
//! domain_id = 0
//! node = "crackbot_controller"
//!
//! [target]                      # what crackbot publishes: the finger tip's target
//! topic = "/crackbot/target"    # geometry_msgs/msg/PoseStamped, reliable, keep last 1
//! frame = "base_link"           # the arm's base frame (header.frame_id)
//! rate_hz = 125.0               # 100–1000
//!
//! [pose]                        # what the arm publishes: where the tool is
//! source = "pose"               # "pose": a PoseStamped topic; "tf": /tf (tf2_msgs/msg/TFMessage)
//! topic = "/crackbot/tool_pose"
//! tool_frame = "tool0"          # with source = "tf": the transform base frame → tool_frame
//!
//! [wrench]                      # optional: the contact wrench (geometry_msgs/msg/WrenchStamped)
//! topic = ""                    # "": none
//! max_force_n = 10.0
//!
//! [motion]
//! travel_height_mm = 5.0
//! travel_speed_mm_s = 50.0
//! approach_speed_mm_s = 5.0
//! max_accel_mm_s2 = 500.0
//! hold_s = 1.0
//!
//! [safety]
//! stale_after_ms = 250.0
//! divergence_mm = 10.0
//! max_reports_per_tick = 50
//! ```

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::limits::Limits;
use crate::motion::cartesian::CartesianSettings;

/// The whole file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2Config {
    /// The DDS domain and node.
    pub dds: Dds,
    /// The target stream.
    pub target: Target,
    /// Where the arm's pose comes from.
    pub pose: PoseSource,
    /// The contact wrench, optional.
    pub wrench: WrenchSource,
    /// How the arm moves.
    pub motion: Motion,
    /// What it tolerates.
    pub safety: Safety,
}

/// `[dds]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dds {
    /// DDS domain id (ROS_DOMAIN_ID), 0–232.
    pub domain_id: u16,
    /// The node's name.
    pub node: String,
}

impl Default for Dds {
    fn default() -> Self {
        Dds {
            domain_id: 0,
            node: "crackbot_controller".into(),
        }
    }
}

/// `[target]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Target {
    /// The topic (`geometry_msgs/msg/PoseStamped`).
    pub topic: String,
    /// The arm's base frame.
    pub frame: String,
    /// Targets per second.
    pub rate_hz: f64,
}

impl Default for Target {
    fn default() -> Self {
        Target {
            topic: "/crackbot/target".into(),
            frame: "base_link".into(),
            rate_hz: 125.0,
        }
    }
}

/// Where the tool's pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// A `geometry_msgs/msg/PoseStamped` topic.
    Pose,
    /// `/tf`: the transform from the base frame to the tool frame.
    Tf,
}

/// `[pose]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PoseSource {
    /// Pose topic or `/tf`.
    pub source: Source,
    /// The pose topic (with `source = "pose"`).
    pub topic: String,
    /// The tool's frame (with `source = "tf"`).
    pub tool_frame: String,
}

impl Default for PoseSource {
    fn default() -> Self {
        PoseSource {
            source: Source::Pose,
            topic: "/crackbot/tool_pose".into(),
            tool_frame: "tool0".into(),
        }
    }
}

/// `[wrench]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WrenchSource {
    /// The topic, `""` for none.
    pub topic: String,
    /// Contact force over this is a fault, N.
    pub max_force_n: f64,
}

impl Default for WrenchSource {
    fn default() -> Self {
        WrenchSource {
            topic: String::new(),
            max_force_n: 10.0,
        }
    }
}

/// `[motion]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Motion {
    /// Height of the finger between slides, mm.
    pub travel_height_mm: f64,
    /// Travel speed between slides, mm/s.
    pub travel_speed_mm_s: f64,
    /// Speed of pressing in and lifting, mm/s.
    pub approach_speed_mm_s: f64,
    /// Acceleration, mm/s².
    pub max_accel_mm_s2: f64,
    /// Time held pressed at a slide's end, s.
    pub hold_s: f64,
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            travel_height_mm: 5.0,
            travel_speed_mm_s: 50.0,
            approach_speed_mm_s: 5.0,
            max_accel_mm_s2: 500.0,
            hold_s: 1.0,
        }
    }
}

/// `[safety]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Safety {
    /// No pose for this long is a fault, ms.
    pub stale_after_ms: f64,
    /// The arm this far from its target is a fault, mm.
    pub divergence_mm: f64,
    /// More pose reports than this between two targets is a flood.
    pub max_reports_per_tick: usize,
}

impl Default for Safety {
    fn default() -> Self {
        Safety {
            stale_after_ms: 250.0,
            divergence_mm: 10.0,
            max_reports_per_tick: 50,
        }
    }
}

/// A configuration that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("reading {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not valid TOML or has unknown keys.
    #[error("{path}: {source}")]
    Parse {
        /// The file.
        path: String,
        /// Why.
        source: Box<toml::de::Error>,
    },
    /// A value is out of range.
    #[error("{key} = {value} is outside {allowed}")]
    Range {
        /// Which key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// A name is empty.
    #[error("{key} is empty")]
    Empty {
        /// Which key.
        key: &'static str,
    },
}

fn within(
    key: &'static str,
    v: f64,
    lo: f64,
    hi: f64,
    allowed: &'static str,
) -> Result<(), ConfigError> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ConfigError::Range {
            key,
            value: v,
            allowed,
        })
    }
}

impl Ros2Config {
    /// Reads and checks a file.
    pub fn load(path: &Path) -> Result<Ros2Config, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
            path: path.display().to_string(),
            source,
        })?;
        let c: Ros2Config = toml::from_str(&text).map_err(|e| ConfigError::Parse {
            path: path.display().to_string(),
            source: Box::new(e),
        })?;
        c.check()?;
        Ok(c)
    }

    /// Checks every value once.
    pub fn check(&self) -> Result<(), ConfigError> {
        within(
            "dds.domain_id",
            f64::from(self.dds.domain_id),
            0.0,
            232.0,
            "[0, 232]",
        )?;
        for (key, v) in [
            ("dds.node", &self.dds.node),
            ("target.topic", &self.target.topic),
            ("target.frame", &self.target.frame),
        ] {
            if v.is_empty() {
                return Err(ConfigError::Empty { key });
            }
        }
        within(
            "target.rate_hz",
            self.target.rate_hz,
            100.0,
            1000.0,
            "[100, 1000] Hz",
        )?;
        let m = &self.motion;
        within(
            "motion.travel_height_mm",
            m.travel_height_mm,
            0.5,
            50.0,
            "[0.5, 50] mm",
        )?;
        within(
            "motion.travel_speed_mm_s",
            m.travel_speed_mm_s,
            0.1,
            500.0,
            "[0.1, 500] mm/s",
        )?;
        within(
            "motion.approach_speed_mm_s",
            m.approach_speed_mm_s,
            0.1,
            50.0,
            "[0.1, 50] mm/s",
        )?;
        within(
            "motion.max_accel_mm_s2",
            m.max_accel_mm_s2,
            10.0,
            10_000.0,
            "[10, 10000] mm/s²",
        )?;
        within("motion.hold_s", m.hold_s, 0.0, 10.0, "[0, 10] s")?;
        let s = &self.safety;
        within(
            "safety.stale_after_ms",
            s.stale_after_ms,
            20.0,
            5000.0,
            "[20, 5000] ms",
        )?;
        within(
            "safety.divergence_mm",
            s.divergence_mm,
            0.5,
            100.0,
            "[0.5, 100] mm",
        )?;
        within(
            "wrench.max_force_n",
            self.wrench.max_force_n,
            0.1,
            200.0,
            "[0.1, 200] N",
        )?;
        if s.max_reports_per_tick < 2 {
            return Err(ConfigError::Range {
                key: "safety.max_reports_per_tick",
                value: s.max_reports_per_tick as f64,
                allowed: "≥ 2",
            });
        }
        Ok(())
    }

    /// The Cartesian arm's settings over `limits`.
    pub fn cartesian(&self, limits: Limits) -> CartesianSettings {
        let mut c = CartesianSettings::new(limits);
        let m = &self.motion;
        c.travel_height_mm = m.travel_height_mm;
        c.travel_speed_mm_s = m.travel_speed_mm_s.min(limits.max_travel_speed_mm_s);
        c.approach_speed_mm_s = m.approach_speed_mm_s;
        c.max_accel_mm_s2 = m.max_accel_mm_s2;
        c.hold_s = m.hold_s;
        c.stale_after_s = self.safety.stale_after_ms / 1e3;
        c.divergence_mm = self.safety.divergence_mm;
        c.max_reports_per_tick = self.safety.max_reports_per_tick;
        c.max_force_n = self.wrench.max_force_n;
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_round_trip_and_a_bad_value_or_key_is_named() {
        let text = toml::to_string(&Ros2Config::default()).expect("toml");
        let back: Ros2Config = toml::from_str(&text).expect("parse");
        assert_eq!(back, Ros2Config::default());
        back.check().expect("defaults are valid");
        let mut c = Ros2Config::default();
        c.target.rate_hz = 50.0;
        let e = c.check().unwrap_err().to_string();
        assert!(e.contains("target.rate_hz = 50"), "{e}");
        let e = toml::from_str::<Ros2Config>("[target]\nrate = 1\n").unwrap_err();
        assert!(e.to_string().contains("unknown field `rate`"), "{e}");
        let c: Ros2Config = toml::from_str("[pose]\nsource = \"tf\"\n").expect("tf");
        assert_eq!(c.pose.source, Source::Tf);
    }
}
