//! A mission's log (as `crackbot_mcap::read_log` decodes it) turned into ROS 2 messages, each
//! stamped with the time it was logged (the host's synchronised clock). Pure: no files.
//!
//! The Foxglove-only channels (the detections drawn on the frame, the plan's scene, the
//! finger's frame transform) have no message of their own here: the candidates come with the
//! report, and `/tf` is made from the arm's pose.

use crackbot_mcap::{JsonTopic, LoggedMessage, MissionLog, Payload};
use serde_json::Value;

use crate::error::RosbagError;
use crate::message::RosMessage;
use crate::msgs::{
    Candidate, CompressedImage, Crack, Header, MissionReport, MissionStatus, Point, Pose,
    PoseStamped, RosLog, StreamHealth, Stroke, TactileSample, TfMessage, Time, Transform,
    TransformStamped, Verdict, IDENTITY, KIND_PASS, KIND_RUNNING,
};
use crate::topics::RosTopic;

/// The surface's frame (x right, y up, z out of the plate; m).
pub const SURFACE_FRAME: &str = "surface";
/// The finger's frame.
pub const FINGER_FRAME: &str = "finger";
/// The camera's frame.
pub const CAMERA_FRAME: &str = "camera";

/// One message of a bag: its topic, when it was logged (Unix ns) and its CDR bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct BagMessage {
    /// Its topic.
    pub topic: RosTopic,
    /// When it was logged, Unix ns.
    pub log_time_ns: u64,
    /// Its CDR bytes (with the encapsulation header).
    pub data: Vec<u8>,
}

/// Reads the fields of one JSON message, naming the message in every error.
struct Fields<'a> {
    m: &'a LoggedMessage,
    v: &'a Value,
}

impl Fields<'_> {
    fn err(&self, field: &'static str, problem: &'static str) -> RosbagError {
        RosbagError::Field {
            topic: self.m.topic.clone(),
            log_time_ns: self.m.log_time_ns,
            field,
            problem,
        }
    }
    /// A number; `None` when absent or null.
    fn opt_f64(&self, field: &'static str) -> Result<Option<f64>, RosbagError> {
        match self.v.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(x) => x
                .as_f64()
                .map(Some)
                .ok_or_else(|| self.err(field, "is not a number")),
        }
    }
    fn f64(&self, field: &'static str) -> Result<f64, RosbagError> {
        self.opt_f64(field)?
            .ok_or_else(|| self.err(field, "is missing"))
    }
    /// A whole number that fits `u64`; `None` when absent or null.
    fn opt_u64(&self, field: &'static str) -> Result<Option<u64>, RosbagError> {
        match self.v.get(field) {
            None | Some(Value::Null) => Ok(None),
            Some(x) => x
                .as_u64()
                .map(Some)
                .ok_or_else(|| self.err(field, "is not a whole number ≥ 0")),
        }
    }
    fn u64(&self, field: &'static str) -> Result<u64, RosbagError> {
        self.opt_u64(field)?
            .ok_or_else(|| self.err(field, "is missing"))
    }
    fn u32(&self, field: &'static str) -> Result<u32, RosbagError> {
        u32::try_from(self.u64(field)?).map_err(|_| self.err(field, "does not fit 32 bits"))
    }
    fn opt_u32(&self, field: &'static str) -> Result<u32, RosbagError> {
        match self.opt_u64(field)? {
            None => Ok(0),
            Some(n) => u32::try_from(n).map_err(|_| self.err(field, "does not fit 32 bits")),
        }
    }
    fn count(&self, field: &'static str) -> Result<u16, RosbagError> {
        u16::try_from(self.u64(field)?).map_err(|_| self.err(field, "is not a 16-bit count"))
    }
    fn str(&self, field: &'static str) -> Result<String, RosbagError> {
        match self.v.get(field) {
            None | Some(Value::Null) => Ok(String::new()),
            Some(Value::String(s)) => Ok(s.clone()),
            Some(_) => Err(self.err(field, "is not a string")),
        }
    }
    /// `[x, y]` in mm, as a point on the surface in m.
    fn xy_mm(&self, field: &'static str) -> Result<Point, RosbagError> {
        let bad = || self.err(field, "is not a pair of numbers [x, y] (mm)");
        let a = self
            .v
            .get(field)
            .and_then(Value::as_array)
            .ok_or_else(bad)?;
        match a.as_slice() {
            [x, y] => Ok(Point::from_mm([
                x.as_f64().ok_or_else(bad)?,
                y.as_f64().ok_or_else(bad)?,
                0.0,
            ])),
            _ => Err(bad()),
        }
    }
}

fn header(ns: u64, frame: &str) -> Header {
    Header {
        stamp: Time::from_ns(ns),
        frame_id: frame.to_string(),
    }
}

/// `msg` encoded for a bag, logged at `ns`.
fn encode(ns: u64, msg: &RosMessage) -> Result<BagMessage, RosbagError> {
    let topic = msg.topic();
    let data = msg.to_cdr().map_err(|source| RosbagError::Cdr {
        topic: topic.name(),
        source,
    })?;
    Ok(BagMessage {
        topic,
        log_time_ns: ns,
        data,
    })
}

fn sample(f: &Fields<'_>, ns: u64) -> Result<TactileSample, RosbagError> {
    Ok(TactileSample {
        header: header(ns, FINGER_FRAME),
        d1: f.count("d1")?,
        d2: f.count("d2")?,
        d3: f.count("d3")?,
        p: f.count("p")?,
        slide: f.opt_u32("slide")?,
        along_mm: f.opt_f64("along_mm")?.unwrap_or(f64::NAN),
    })
}

fn arm_pose(f: &Fields<'_>, ns: u64) -> Result<Vec<RosMessage>, RosbagError> {
    let at = Point::from_mm([f.f64("x_mm")?, f.f64("y_mm")?, f.f64("z_mm")?]);
    let pose = PoseStamped {
        header: header(ns, SURFACE_FRAME),
        pose: Pose {
            position: at,
            orientation: IDENTITY,
        },
    };
    let tf = TfMessage {
        transforms: vec![TransformStamped {
            header: header(ns, SURFACE_FRAME),
            child_frame_id: FINGER_FRAME.into(),
            transform: Transform {
                translation: at,
                rotation: IDENTITY,
            },
        }],
    };
    Ok(vec![RosMessage::ArmPose(pose), RosMessage::Tf(tf)])
}

fn pass(f: &Fields<'_>, ns: u64) -> Result<Vec<RosMessage>, RosbagError> {
    let (id, candidate, samples) = (f.u32("id")?, f.opt_u32("candidate")?, f.u32("samples")?);
    let stroke = Stroke {
        header: header(ns, SURFACE_FRAME),
        id,
        candidate,
        start: f.xy_mm("start_mm")?,
        end: f.xy_mm("end_mm")?,
        samples,
        recording: f.str("recording")?,
    };
    let verdict = Verdict {
        header: header(ns, SURFACE_FRAME),
        kind: KIND_PASS,
        stroke: id,
        candidate,
        surface: f.str("class")?,
        confidence: f.opt_f64("confidence")?.unwrap_or(f64::NAN),
        width_mm: f.opt_f64("width_mm")?.unwrap_or(f64::NAN),
        count: samples,
    };
    Ok(vec![
        RosMessage::Stroke(stroke),
        RosMessage::Verdict(verdict),
    ])
}

fn feeling(f: &Fields<'_>, ns: u64) -> Result<Verdict, RosbagError> {
    Ok(Verdict {
        header: header(ns, SURFACE_FRAME),
        kind: KIND_RUNNING,
        stroke: f.u32("slide")?,
        candidate: 0,
        surface: f.str("class")?,
        confidence: f.opt_f64("confidence")?.unwrap_or(f64::NAN),
        width_mm: f.opt_f64("width_mm")?.unwrap_or(f64::NAN),
        count: f.opt_u32("windows")?,
    })
}

fn health(f: &Fields<'_>, ns: u64) -> Result<StreamHealth, RosbagError> {
    Ok(StreamHealth {
        header: header(ns, FINGER_FRAME),
        sample_rate_hz: f.f64("sample_rate_hz")?,
        frames: f.u64("frames")?,
        crc_errors: f.opt_u64("crc_errors")?.unwrap_or(0),
        gaps: f.opt_u64("gaps")?.unwrap_or(0),
        missing_frames: f.opt_u64("missing_frames")?.unwrap_or(0),
        link_sent: f.opt_u64("link_sent")?.unwrap_or(0),
        link_retries: f.opt_u64("link_retries")?.unwrap_or(0),
        link_rejected: f.opt_u64("link_rejected")?.unwrap_or(0),
        state_age_ms: f.opt_f64("state_age_ms")?.unwrap_or(f64::NAN),
    })
}

/// The elements of array `field` (none when absent), each read by `read`.
fn each<T>(
    f: &Fields<'_>,
    field: &'static str,
    read: impl Fn(&Fields<'_>) -> Result<T, RosbagError>,
) -> Result<Vec<T>, RosbagError> {
    match f.v.get(field) {
        None | Some(Value::Null) => Ok(Vec::new()),
        Some(Value::Array(a)) => a.iter().map(|v| read(&Fields { m: f.m, v })).collect(),
        Some(_) => Err(f.err(field, "is not an array")),
    }
}

fn report(f: &Fields<'_>, ns: u64) -> Result<MissionReport, RosbagError> {
    let candidates = each(f, "candidates", |c| {
        Ok(Candidate {
            id: c.u32("id")?,
            centre: c.xy_mm("centre_mm")?,
            axis_deg: c.opt_f64("axis_deg")?.unwrap_or(f64::NAN),
            length_mm: c.opt_f64("length_mm")?.unwrap_or(f64::NAN),
            width_mm: c.opt_f64("width_mm")?.unwrap_or(f64::NAN),
            score: c.opt_f64("score")?.unwrap_or(f64::NAN) as f32,
        })
    })?;
    let cracks = each(f, "cracks", |c| {
        let range = c.v.get("width_range_mm").and_then(Value::as_array);
        let bound = |k: usize| {
            range
                .and_then(|r| r.get(k))
                .and_then(Value::as_f64)
                .unwrap_or(f64::NAN)
        };
        Ok(Crack {
            candidate: c.opt_u32("candidate")?,
            position: c.xy_mm("position_mm")?,
            width_mm: c.opt_f64("width_mm")?.unwrap_or(f64::NAN),
            width_low_mm: bound(0),
            width_high_mm: bound(1),
            confidence: c.opt_f64("confidence")?.unwrap_or(f64::NAN),
        })
    })?;
    let len = |field: &'static str| {
        f.v.get(field)
            .and_then(Value::as_array)
            .map_or(0, |a| a.len() as u32)
    };
    Ok(MissionReport {
        header: header(ns, SURFACE_FRAME),
        mode: f.str("mode")?,
        scene: f.str("scene")?,
        candidates,
        cracks,
        rejected: len("rejected"),
        passes: len("passes"),
        elapsed_s: f.opt_f64("elapsed_s")?.unwrap_or(f64::NAN),
        exploration_s: f.opt_f64("exploration_s")?.unwrap_or(f64::NAN),
        report_json: f.v.to_string(),
    })
}

/// The ROS 2 messages of one JSON message of the log.
fn json(m: &LoggedMessage, v: &Value, topic: JsonTopic) -> Result<Vec<RosMessage>, RosbagError> {
    let (f, ns) = (Fields { m, v }, m.log_time_ns);
    let msg = match topic {
        JsonTopic::ArmPose => return arm_pose(&f, ns),
        JsonTopic::Verdict => return pass(&f, ns),
        JsonTopic::Tactile => RosMessage::Tactile(sample(&f, ns)?),
        JsonTopic::Slide => RosMessage::StrokeSample(sample(&f, ns)?),
        JsonTopic::Feeling => RosMessage::Feeling(feeling(&f, ns)?),
        JsonTopic::Health => RosMessage::Health(health(&f, ns)?),
        JsonTopic::Status => {
            let status = MissionStatus {
                header: header(ns, SURFACE_FRAME),
                stage: f.str("stage")?,
                detail: f.str("detail")?,
            };
            RosMessage::Status(status)
        }
        JsonTopic::Report => RosMessage::Report(report(&f, ns)?),
    };
    Ok(vec![msg])
}

/// `foxglove.Log`'s level (1 debug … 5 fatal) as `rcl_interfaces/Log`'s (10 … 50).
fn ros_level(foxglove: i32) -> u8 {
    (foxglove.clamp(1, 5) * 10) as u8
}

/// The ROS 2 messages of one message of the log (none for the Foxglove-only channels), typed:
/// what a live node publishes.
pub fn ros_messages(m: &LoggedMessage) -> Result<Vec<RosMessage>, RosbagError> {
    let ns = m.log_time_ns;
    match &m.payload {
        Payload::Image { format, data } => {
            let image = CompressedImage {
                header: header(ns, CAMERA_FRAME),
                format: format.clone(),
                data: data.clone(),
            };
            Ok(vec![RosMessage::Image(image)])
        }
        Payload::Log { level, message } => {
            let log = RosLog {
                stamp: Time::from_ns(ns),
                level: ros_level(*level),
                name: "crackbot".into(),
                msg: message.clone(),
                file: String::new(),
                function: String::new(),
                line: 0,
            };
            Ok(vec![RosMessage::Log(log)])
        }
        Payload::Json(v) => match JsonTopic::of_topic(&m.topic) {
            Some(topic) => json(m, v, topic),
            None => Ok(Vec::new()),
        },
        Payload::Decoded | Payload::Unknown => Ok(Vec::new()),
    }
}

/// The ROS 2 messages of one message of the log, encoded for a bag.
pub fn convert_message(m: &LoggedMessage) -> Result<Vec<BagMessage>, RosbagError> {
    ros_messages(m)?
        .iter()
        .map(|r| encode(m.log_time_ns, r))
        .collect()
}

/// Every ROS 2 message of `log`, in the log's order.
pub fn convert(log: &MissionLog) -> Result<Vec<BagMessage>, RosbagError> {
    let mut out = Vec::with_capacity(log.messages.len());
    for m in &log.messages {
        out.extend(convert_message(m)?);
    }
    Ok(out)
}
