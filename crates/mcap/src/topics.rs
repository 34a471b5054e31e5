//! The log's channels: their topics and, for the JSON ones, their JSON Schemas.

/// A channel with a Foxglove well-known schema (protobuf).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Topic {
    /// The camera frame the mission looked at (`foxglove.CompressedImage`, PNG).
    Image,
    /// The detections drawn on the frame: boxes, centre lines, scores
    /// (`foxglove.ImageAnnotations`, pixels).
    Detections,
    /// The plan and the candidates on the surface (`foxglove.SceneUpdate`, frame `surface`, m).
    Scene,
    /// The finger's pose over the surface (`foxglove.FrameTransform`, `surface` → `finger`, m).
    Transform,
    /// What the mission logs (`foxglove.Log`).
    Log,
}

impl Topic {
    /// Every one, in the order the log creates them.
    pub const ALL: [Topic; 5] = [
        Topic::Image,
        Topic::Detections,
        Topic::Scene,
        Topic::Transform,
        Topic::Log,
    ];

    /// Its topic.
    pub fn topic(self) -> &'static str {
        match self {
            Topic::Image => "/camera/image",
            Topic::Detections => "/camera/detections",
            Topic::Scene => "/plan",
            Topic::Transform => "/tf",
            Topic::Log => "/log",
        }
    }

    /// Its schema's name.
    pub fn schema(self) -> &'static str {
        match self {
            Topic::Image => "foxglove.CompressedImage",
            Topic::Detections => "foxglove.ImageAnnotations",
            Topic::Scene => "foxglove.SceneUpdate",
            Topic::Transform => "foxglove.FrameTransform",
            Topic::Log => "foxglove.Log",
        }
    }
}

/// A channel of JSON messages, each with its JSON Schema in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum JsonTopic {
    /// One sensor sample: time, the four channels (counts), the slide and the finger's position
    /// along its stroke when it is down in one (400 Hz).
    Tactile,
    /// One sample of a recorded stroke, as its pass was judged from it: time, the four
    /// channels, the slide and the position along the stroke interpolated from the arm's states.
    Slide,
    /// The arm's pose in surface mm and what it is doing (100 Hz).
    ArmPose,
    /// A slide pass judged (the report's pass record).
    Verdict,
    /// The running verdict of the stroke under way (shown only).
    Feeling,
    /// The sensor stream's and the link's counters (every 0.5 s).
    Health,
    /// The mission's stage.
    Status,
    /// The mission's report, once, at its end.
    Report,
}

impl JsonTopic {
    /// Every one, in the order the log creates them.
    pub const ALL: [JsonTopic; 8] = [
        JsonTopic::Tactile,
        JsonTopic::Slide,
        JsonTopic::ArmPose,
        JsonTopic::Verdict,
        JsonTopic::Feeling,
        JsonTopic::Health,
        JsonTopic::Status,
        JsonTopic::Report,
    ];

    /// Its topic.
    pub fn topic(self) -> &'static str {
        match self {
            JsonTopic::Tactile => "/tactile",
            JsonTopic::Slide => "/slide",
            JsonTopic::ArmPose => "/arm/pose",
            JsonTopic::Verdict => "/verdicts",
            JsonTopic::Feeling => "/feeling",
            JsonTopic::Health => "/health",
            JsonTopic::Status => "/mission/status",
            JsonTopic::Report => "/mission/report",
        }
    }

    /// The topic's channel, by its name.
    pub fn of_topic(topic: &str) -> Option<JsonTopic> {
        JsonTopic::ALL.into_iter().find(|t| t.topic() == topic)
    }

    /// Its schema's name.
    pub fn schema(self) -> &'static str {
        match self {
            JsonTopic::Tactile => "crackbot.TactileSample",
            JsonTopic::Slide => "crackbot.StrokeSample",
            JsonTopic::ArmPose => "crackbot.ArmPose",
            JsonTopic::Verdict => "crackbot.PassRecord",
            JsonTopic::Feeling => "crackbot.Feeling",
            JsonTopic::Health => "crackbot.StreamHealth",
            JsonTopic::Status => "crackbot.MissionStatus",
            JsonTopic::Report => "crackbot.InspectReport",
        }
    }

    /// Its JSON Schema: the fields a viewer plots (an object may carry more).
    pub fn json_schema(self) -> String {
        let (title, props, required): (&str, &[(&str, &str)], &[&str]) = match self {
            JsonTopic::Tactile => (
                "One sensor sample on the host's clock",
                &[
                    ("t_s", "number"),
                    ("d1", "integer"),
                    ("d2", "integer"),
                    ("d3", "integer"),
                    ("p", "integer"),
                    ("slide", "integer"),
                    ("along_mm", "number"),
                ],
                &["t_s", "d1", "d2", "d3", "p"],
            ),
            JsonTopic::Slide => (
                "One sample of a recorded stroke",
                &[
                    ("t_s", "number"),
                    ("slide", "integer"),
                    ("along_mm", "number"),
                    ("d1", "integer"),
                    ("d2", "integer"),
                    ("d3", "integer"),
                    ("p", "integer"),
                ],
                &["t_s", "slide", "along_mm", "d1", "d2", "d3", "p"],
            ),
            JsonTopic::ArmPose => (
                "The arm's pose over the surface, mm",
                &[
                    ("t_s", "number"),
                    ("x_mm", "number"),
                    ("y_mm", "number"),
                    ("z_mm", "number"),
                    ("slide", "integer"),
                    ("along_mm", "number"),
                ],
                &["t_s", "x_mm", "y_mm", "z_mm"],
            ),
            JsonTopic::Verdict => (
                "A slide pass and its verdict",
                &[
                    ("id", "integer"),
                    ("candidate", "integer"),
                    ("class", "string"),
                    ("confidence", "number"),
                    ("width_mm", "number"),
                    ("samples", "integer"),
                    ("recording", "string"),
                ],
                &["id", "samples"],
            ),
            JsonTopic::Feeling => (
                "The running verdict of the stroke under way",
                &[
                    ("slide", "integer"),
                    ("class", "string"),
                    ("confidence", "number"),
                    ("width_mm", "number"),
                    ("windows", "integer"),
                    ("along_mm", "number"),
                ],
                &["slide", "class", "confidence"],
            ),
            JsonTopic::Health => (
                "The sensor stream's and the link's counters",
                &[
                    ("sample_rate_hz", "number"),
                    ("frames", "integer"),
                    ("crc_errors", "integer"),
                    ("gaps", "integer"),
                    ("missing_frames", "integer"),
                    ("link_sent", "integer"),
                    ("link_retries", "integer"),
                    ("link_rejected", "integer"),
                    ("state_age_ms", "number"),
                ],
                &["sample_rate_hz", "frames"],
            ),
            JsonTopic::Status => (
                "The mission's stage",
                &[("stage", "string"), ("detail", "string")],
                &["stage"],
            ),
            JsonTopic::Report => ("The mission's report (report.json)", &[], &[]),
        };
        let properties: serde_json::Map<String, serde_json::Value> = props
            .iter()
            .map(|(name, ty)| {
                let ty = if required.contains(name) {
                    serde_json::json!(ty)
                } else {
                    serde_json::json!([ty, "null"])
                };
                ((*name).to_string(), serde_json::json!({ "type": ty }))
            })
            .collect();
        serde_json::json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": title,
            "type": "object",
            "properties": properties,
            "required": required,
        })
        .to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topics_are_distinct_and_found_by_name() {
        let mut all: Vec<&str> = Topic::ALL.iter().map(|t| t.topic()).collect();
        all.extend(JsonTopic::ALL.iter().map(|t| t.topic()));
        let n = all.len();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), n);
        for t in JsonTopic::ALL {
            assert_eq!(JsonTopic::of_topic(t.topic()), Some(t));
        }
        assert_eq!(JsonTopic::of_topic("/camera/image"), None);
    }

    #[test]
    fn json_schemas_are_objects_naming_their_required_fields() {
        for t in JsonTopic::ALL {
            let s: serde_json::Value = serde_json::from_str(&t.json_schema()).unwrap();
            assert_eq!(s["type"], "object");
            for r in s["required"].as_array().unwrap() {
                assert!(s["properties"].get(r.as_str().unwrap()).is_some(), "{t:?}");
            }
        }
    }
}
