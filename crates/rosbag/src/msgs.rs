//! The ROS 2 messages crackbot speaks (a bag's, the live topics', the ROS 2 arm's), as serde
//! types whose fields follow the `.msg` definitions in order (CDR encodes by order), and
//! each written type's definition as rosbag2 embeds it (`ros2msg`: the type's own text, then every type
//! it uses, each once, after a line of 80 `=` and `MSG: package/Type`).
//!
//! crackbot's own types are read from `ros/crackbot_msgs/msg/` (the interface package a ROS 2
//! workspace builds), so the bag and the package cannot disagree.

use serde::{Deserialize, Serialize};

/// `builtin_interfaces/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Time {
    /// Seconds since the Unix epoch.
    pub sec: i32,
    /// And nanoseconds.
    pub nanosec: u32,
}

impl Time {
    /// The time of `ns` Unix nanoseconds (clamped to what `sec: i32` holds).
    pub fn from_ns(ns: u64) -> Self {
        let sec = (ns / 1_000_000_000).min(i32::MAX as u64) as i32;
        Time {
            sec,
            nanosec: (ns % 1_000_000_000) as u32,
        }
    }

    /// The wall clock now (ROS time).
    pub fn now() -> Self {
        let d = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Time {
            sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX),
            nanosec: d.subsec_nanos(),
        }
    }
}

/// `std_msgs/Header`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Header {
    /// When.
    pub stamp: Time,
    /// In which frame.
    pub frame_id: String,
}

/// `geometry_msgs/Point` (and `Vector3`: the same fields), m.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// x, m.
    pub x: f64,
    /// y, m.
    pub y: f64,
    /// z, m.
    pub z: f64,
}

impl Point {
    /// The point of `mm` (x, y, z in millimetres).
    pub fn from_mm([x, y, z]: [f64; 3]) -> Self {
        Point {
            x: x / 1000.0,
            y: y / 1000.0,
            z: z / 1000.0,
        }
    }
}

/// `geometry_msgs/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// The identity rotation.
pub const IDENTITY: Quaternion = Quaternion {
    x: 0.0,
    y: 0.0,
    z: 0.0,
    w: 1.0,
};

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// Position, m.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseStamped {
    /// When and where.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/Transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, m.
    pub translation: Point,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TransformStamped {
    /// When, and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// The child in the parent.
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `geometry_msgs/Wrench`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Wrench {
    /// N.
    pub force: Point,
    /// N·m.
    pub torque: Point,
}

/// `geometry_msgs/WrenchStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct WrenchStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The wrench.
    pub wrench: Wrench,
}

/// `sensor_msgs/CompressedImage`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CompressedImage {
    /// When, and the camera's frame.
    pub header: Header,
    /// "png", "jpeg".
    pub format: String,
    /// The encoded image.
    pub data: Vec<u8>,
}

/// `rcl_interfaces/Log` (what `/rosout` carries).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RosLog {
    /// When.
    pub stamp: Time,
    /// 10 debug, 20 info, 30 warn, 40 error, 50 fatal.
    pub level: u8,
    /// The logger's name.
    pub name: String,
    /// The text.
    pub msg: String,
    /// Source file ("" when none).
    pub file: String,
    /// Function ("" when none).
    pub function: String,
    /// Line (0 when none).
    pub line: u32,
}

/// `crackbot_msgs/TactileSample`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TactileSample {
    /// When the host received it; frame "finger".
    pub header: Header,
    /// Deformation, left, counts.
    pub d1: u16,
    /// Deformation, right, counts.
    pub d2: u16,
    /// Deformation, back, counts.
    pub d3: u16,
    /// Proximity, counts.
    pub p: u16,
    /// The stroke under way (0: none).
    pub slide: u32,
    /// Where along it, mm (NaN: none).
    pub along_mm: f64,
}

/// `crackbot_msgs/Stroke`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stroke {
    /// When it ended; frame "surface".
    pub header: Header,
    /// The pass's id.
    pub id: u32,
    /// Its candidate (0: none).
    pub candidate: u32,
    /// Start, m.
    pub start: Point,
    /// End, m.
    pub end: Point,
    /// Samples recorded.
    pub samples: u32,
    /// Its CSV file ("" when none).
    pub recording: String,
}

/// `crackbot_msgs/Verdict`'s `KIND_PASS`.
pub const KIND_PASS: u8 = 0;
/// `crackbot_msgs/Verdict`'s `KIND_RUNNING`.
pub const KIND_RUNNING: u8 = 1;

/// `crackbot_msgs/Verdict`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    /// When it was read.
    pub header: Header,
    /// [`KIND_PASS`] or [`KIND_RUNNING`].
    pub kind: u8,
    /// The pass.
    pub stroke: u32,
    /// Its candidate (0: none).
    pub candidate: u32,
    /// The class read ("" when none).
    pub surface: String,
    /// Its confidence (NaN: none).
    pub confidence: f64,
    /// The width read, mm (NaN: none).
    pub width_mm: f64,
    /// Windows read, or samples of the pass.
    pub count: u32,
}

/// `crackbot_msgs/Candidate`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Candidate {
    /// Its id.
    pub id: u32,
    /// Its centre, m.
    pub centre: Point,
    /// Its axis, degrees.
    pub axis_deg: f64,
    /// Its length, mm.
    pub length_mm: f64,
    /// Its width as seen, mm.
    pub width_mm: f64,
    /// The detector's score.
    pub score: f32,
}

/// `crackbot_msgs/Crack`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Crack {
    /// Its candidate.
    pub candidate: u32,
    /// Where, m.
    pub position: Point,
    /// Width, mm.
    pub width_mm: f64,
    /// The width vote's 10 % quantile, mm.
    pub width_low_mm: f64,
    /// Its 90 % quantile, mm.
    pub width_high_mm: f64,
    /// Confidence.
    pub confidence: f64,
}

/// `crackbot_msgs/MissionStatus`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissionStatus {
    /// When it changed.
    pub header: Header,
    /// The stage.
    pub stage: String,
    /// Free text.
    pub detail: String,
}

/// `crackbot_msgs/MissionReport`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MissionReport {
    /// When it was written.
    pub header: Header,
    /// The mode.
    pub mode: String,
    /// The scene.
    pub scene: String,
    /// The camera's candidates.
    pub candidates: Vec<Candidate>,
    /// The confirmed cracks.
    pub cracks: Vec<Crack>,
    /// Candidates rejected.
    pub rejected: u32,
    /// Slides made.
    pub passes: u32,
    /// Whole mission, s.
    pub elapsed_s: f64,
    /// Exploration, s.
    pub exploration_s: f64,
    /// report.json.
    pub report_json: String,
}

/// `crackbot_msgs/StreamHealth`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StreamHealth {
    /// When.
    pub header: Header,
    /// Samples a second.
    pub sample_rate_hz: f64,
    /// Frames read.
    pub frames: u64,
    /// Frames with a bad CRC.
    pub crc_errors: u64,
    /// Gaps in the sequence.
    pub gaps: u64,
    /// Frames missing in them.
    pub missing_frames: u64,
    /// Link commands sent.
    pub link_sent: u64,
    /// Retried.
    pub link_retries: u64,
    /// Rejected.
    pub link_rejected: u64,
    /// Age of the arm's last state, ms (NaN: none).
    pub state_age_ms: f64,
}

/// A message type a bag holds: its ROS 2 name, its definition, and the types it uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MsgType {
    /// `builtin_interfaces/msg/Time`.
    Time,
    /// `std_msgs/msg/Header`.
    Header,
    /// `geometry_msgs/msg/Point`.
    Point,
    /// `geometry_msgs/msg/Vector3`.
    Vector3,
    /// `geometry_msgs/msg/Quaternion`.
    Quaternion,
    /// `geometry_msgs/msg/Pose`.
    Pose,
    /// `geometry_msgs/msg/PoseStamped`.
    PoseStamped,
    /// `geometry_msgs/msg/Transform`.
    Transform,
    /// `geometry_msgs/msg/TransformStamped`.
    TransformStamped,
    /// `tf2_msgs/msg/TFMessage`.
    TfMessage,
    /// `sensor_msgs/msg/CompressedImage`.
    CompressedImage,
    /// `rcl_interfaces/msg/Log`.
    Log,
    /// `crackbot_msgs/msg/TactileSample`.
    TactileSample,
    /// `crackbot_msgs/msg/Stroke`.
    Stroke,
    /// `crackbot_msgs/msg/Verdict`.
    Verdict,
    /// `crackbot_msgs/msg/Candidate`.
    Candidate,
    /// `crackbot_msgs/msg/Crack`.
    Crack,
    /// `crackbot_msgs/msg/MissionStatus`.
    MissionStatus,
    /// `crackbot_msgs/msg/MissionReport`.
    MissionReport,
    /// `crackbot_msgs/msg/StreamHealth`.
    StreamHealth,
}

impl MsgType {
    /// Its package and name (`package/Type`, as `MSG:` lines and field types spell it).
    pub fn short_name(self) -> &'static str {
        use MsgType::*;
        match self {
            Time => "builtin_interfaces/Time",
            Header => "std_msgs/Header",
            Point => "geometry_msgs/Point",
            Vector3 => "geometry_msgs/Vector3",
            Quaternion => "geometry_msgs/Quaternion",
            Pose => "geometry_msgs/Pose",
            PoseStamped => "geometry_msgs/PoseStamped",
            Transform => "geometry_msgs/Transform",
            TransformStamped => "geometry_msgs/TransformStamped",
            TfMessage => "tf2_msgs/TFMessage",
            CompressedImage => "sensor_msgs/CompressedImage",
            Log => "rcl_interfaces/Log",
            TactileSample => "crackbot_msgs/TactileSample",
            Stroke => "crackbot_msgs/Stroke",
            Verdict => "crackbot_msgs/Verdict",
            Candidate => "crackbot_msgs/Candidate",
            Crack => "crackbot_msgs/Crack",
            MissionStatus => "crackbot_msgs/MissionStatus",
            MissionReport => "crackbot_msgs/MissionReport",
            StreamHealth => "crackbot_msgs/StreamHealth",
        }
    }

    /// Its ROS 2 type name (`package/msg/Type`), as the bag's topics name it.
    pub fn name(self) -> String {
        self.short_name().replacen('/', "/msg/", 1)
    }

    /// Its `.msg` text.
    pub fn text(self) -> &'static str {
        use MsgType::*;
        match self {
            Time => "int32 sec\nuint32 nanosec\n",
            Header => "builtin_interfaces/Time stamp\nstring frame_id\n",
            Point | Vector3 => "float64 x\nfloat64 y\nfloat64 z\n",
            Quaternion => "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
            Pose => "Point position\nQuaternion orientation\n",
            PoseStamped => "std_msgs/Header header\nPose pose\n",
            Transform => "Vector3 translation\nQuaternion rotation\n",
            TransformStamped => {
                "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"
            }
            TfMessage => "geometry_msgs/TransformStamped[] transforms\n",
            CompressedImage => "std_msgs/Header header\nstring format\nuint8[] data\n",
            Log => concat!(
                "byte DEBUG=10\nbyte INFO=20\nbyte WARN=30\nbyte ERROR=40\nbyte FATAL=50\n",
                "builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\n",
                "string file\nstring function\nuint32 line\n"
            ),
            TactileSample => include_str!("../../../ros/crackbot_msgs/msg/TactileSample.msg"),
            Stroke => include_str!("../../../ros/crackbot_msgs/msg/Stroke.msg"),
            Verdict => include_str!("../../../ros/crackbot_msgs/msg/Verdict.msg"),
            Candidate => include_str!("../../../ros/crackbot_msgs/msg/Candidate.msg"),
            Crack => include_str!("../../../ros/crackbot_msgs/msg/Crack.msg"),
            MissionStatus => include_str!("../../../ros/crackbot_msgs/msg/MissionStatus.msg"),
            MissionReport => include_str!("../../../ros/crackbot_msgs/msg/MissionReport.msg"),
            StreamHealth => include_str!("../../../ros/crackbot_msgs/msg/StreamHealth.msg"),
        }
    }

    /// The types its fields use directly.
    pub fn uses(self) -> &'static [MsgType] {
        use MsgType::*;
        match self {
            Time | Point | Vector3 | Quaternion => &[],
            Header | Log => &[Time],
            Pose => &[Point, Quaternion],
            PoseStamped => &[Header, Pose],
            Transform => &[Vector3, Quaternion],
            TransformStamped => &[Header, Transform],
            TfMessage => &[TransformStamped],
            CompressedImage | TactileSample | MissionStatus | StreamHealth => &[Header],
            Stroke => &[Header, Point],
            Verdict => &[Header],
            Candidate | Crack => &[Point],
            MissionReport => &[Header, Candidate, Crack],
        }
    }

    /// Its definition as rosbag2 embeds it: its text, then each type it uses (depth first,
    /// each once) after a separator line and `MSG: package/Type`.
    pub fn definition(self) -> String {
        let mut order = Vec::new();
        fn visit(t: MsgType, order: &mut Vec<MsgType>) {
            for &u in t.uses() {
                if !order.contains(&u) {
                    order.push(u);
                    visit(u, order);
                }
            }
        }
        visit(self, &mut order);
        let mut out = self.text().trim_end().to_string();
        for t in order {
            out.push('\n');
            out.push_str(&"=".repeat(80));
            out.push_str("\nMSG: ");
            out.push_str(t.short_name());
            out.push('\n');
            out.push_str(t.text().trim_end());
        }
        out.push('\n');
        out
    }
}

/// The CDR bytes of `msg` as a bag stores them: the encapsulation header of little-endian
/// plain CDR (`00 01 00 00`), then the message.
pub fn to_cdr<T: Serialize>(msg: &T) -> Result<Vec<u8>, cdr_encoding::Error> {
    let body = cdr_encoding::to_vec::<T, byteorder::LittleEndian>(msg)?;
    let mut out = Vec::with_capacity(body.len() + 4);
    out.extend_from_slice(&[0, 1, 0, 0]);
    out.extend_from_slice(&body);
    Ok(out)
}
