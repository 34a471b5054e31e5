//! Key expressions: everything a robot says lives under `crackbot/<robot>/…`.
//!
//! | key | what | how |
//! |---|---|---|
//! | `crackbot/<robot>/tactile` | sensor samples, 400 Hz, in ~25 ms chunks | put |
//! | `crackbot/<robot>/camera` | the mission's frame (PNG) and its surface → pixel homography | put |
//! | `crackbot/<robot>/detections` | candidates in surface mm | put |
//! | `crackbot/<robot>/plan` | the planned slides | put |
//! | `crackbot/<robot>/verdicts` | each judged slide pass | put |
//! | `crackbot/<robot>/health` | heartbeat (≥ 4 Hz) with the stream's counters | put |
//! | `crackbot/<robot>/mission` | the mission's stage; the report at the end | put |
//! | `crackbot/<robot>/state` | the latest of each topic, every verdict so far | queryable |
//! | `crackbot/<robot>/command` | signed mission commands, answered accept/refuse | queryable |
//! | `crackbot/<robot>/alive` | the robot's liveliness token | liveliness |

/// First chunk of every key.
pub const ROOT: &str = "crackbot";

/// Longest robot name.
pub const MAX_NAME_LEN: usize = 64;

/// The published topics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Topic {
    /// Sensor samples.
    Tactile,
    /// The frame.
    Camera,
    /// Candidates.
    Detections,
    /// Planned slides.
    Plan,
    /// Judged passes.
    Verdicts,
    /// Heartbeat.
    Health,
    /// Mission stage and report.
    Mission,
}

impl Topic {
    /// Every topic.
    pub const ALL: [Topic; 7] = [
        Topic::Tactile,
        Topic::Camera,
        Topic::Detections,
        Topic::Plan,
        Topic::Verdicts,
        Topic::Health,
        Topic::Mission,
    ];

    /// Its last key chunk.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Tactile => "tactile",
            Topic::Camera => "camera",
            Topic::Detections => "detections",
            Topic::Plan => "plan",
            Topic::Verdicts => "verdicts",
            Topic::Health => "health",
            Topic::Mission => "mission",
        }
    }
}

/// A robot's name is usable in keys: 1–64 ASCII letters, digits, `-` or `_` (no `/`, `*`, `$`,
/// `?`, `#`, which Zenoh reserves). The error says what is wrong.
pub fn check_robot_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("a robot name cannot be empty".into());
    }
    if name.len() > MAX_NAME_LEN {
        return Err(format!(
            "robot name of {} characters is too long (at most {MAX_NAME_LEN})",
            name.len()
        ));
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || *c == '-' || *c == '_'))
    {
        return Err(format!(
            "robot name {name:?} contains {c:?}: use letters, digits, '-' and '_'"
        ));
    }
    Ok(())
}

/// `crackbot/<robot>/<topic>`.
pub fn topic_key(robot: &str, topic: Topic) -> String {
    format!("{ROOT}/{robot}/{}", topic.name())
}

/// `crackbot/<robot>/state`.
pub fn state_key(robot: &str) -> String {
    format!("{ROOT}/{robot}/state")
}

/// `crackbot/<robot>/command`.
pub fn command_key(robot: &str) -> String {
    format!("{ROOT}/{robot}/command")
}

/// `crackbot/<robot>/alive`.
pub fn alive_key(robot: &str) -> String {
    format!("{ROOT}/{robot}/alive")
}

/// The robot named by a key under [`ROOT`] (`None` for a wildcard or an unusable name).
pub fn robot_of(key: &str) -> Option<&str> {
    let rest = key.strip_prefix(ROOT)?.strip_prefix('/')?;
    let robot = rest.split('/').next()?;
    check_robot_name(robot).is_ok().then_some(robot)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_that_zenoh_would_misread_are_refused_with_the_reason() {
        assert!(check_robot_name("r1").is_ok());
        assert!(check_robot_name("tank-7_b").is_ok());
        assert!(check_robot_name("").unwrap_err().contains("empty"));
        assert!(check_robot_name("a/b").unwrap_err().contains("'/'"));
        assert!(check_robot_name("a*").unwrap_err().contains("'*'"));
        assert!(check_robot_name(&"x".repeat(65))
            .unwrap_err()
            .contains("too long"));
    }

    #[test]
    fn keys_name_their_robot() {
        assert_eq!(topic_key("r1", Topic::Tactile), "crackbot/r1/tactile");
        assert_eq!(robot_of("crackbot/r1/tactile"), Some("r1"));
        assert_eq!(robot_of("crackbot/r2/alive"), Some("r2"));
        assert_eq!(robot_of("other/r1/tactile"), None);
        assert_eq!(robot_of("crackbot"), None);
        assert_eq!(robot_of("crackbot/*/state"), None);
        assert_eq!(robot_of("crackbot/**"), None);
    }
}
