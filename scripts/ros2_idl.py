"""ROS 2 message types for Eclipse Cyclone DDS's Python binding, under their DDS names, shared by
the scripts that play ROS 2 peers without ROS (scripts/dds_arm.py, scripts/ros2_live_check.py).

ROS 2's DDS conventions: a message `pkg/msg/Name` is the DDS type `pkg::msg::dds_::Name_`, a final
struct in plain (XCDR1) CDR with the message's fields in order (nested messages inline, `string` as
a CDR string, unbounded arrays as sequences). crackbot's own types follow ros/crackbot_msgs/msg.
"""
from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float32, float64, int32, sequence, uint8, uint16, uint32


# --- Standard ROS 2 messages. ---
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32

@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str

@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64

@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64

@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion

@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    header: Header
    pose: Pose

@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64

@dataclass
class Transform(IdlStruct, typename="geometry_msgs::msg::dds_::Transform_"):
    translation: Vector3
    rotation: Quaternion

@dataclass
class TransformStamped(IdlStruct, typename="geometry_msgs::msg::dds_::TransformStamped_"):
    header: Header
    child_frame_id: str
    transform: Transform

@dataclass
class TFMessage(IdlStruct, typename="tf2_msgs::msg::dds_::TFMessage_"):
    transforms: sequence[TransformStamped]  # a ROS unbounded array: a CDR sequence

@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    force: Vector3
    torque: Vector3

@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    header: Header
    wrench: Wrench


# --- crackbot_msgs (ros/crackbot_msgs/msg). ---
@dataclass
class TactileSample(IdlStruct, typename="crackbot_msgs::msg::dds_::TactileSample_"):
    header: Header
    d1: uint16
    d2: uint16
    d3: uint16
    p: uint16
    slide: uint32
    along_mm: float64

@dataclass
class Verdict(IdlStruct, typename="crackbot_msgs::msg::dds_::Verdict_"):
    header: Header
    kind: uint8
    stroke: uint32
    candidate: uint32
    surface: str
    confidence: float64
    width_mm: float64
    count: uint32

@dataclass
class Stroke(IdlStruct, typename="crackbot_msgs::msg::dds_::Stroke_"):
    header: Header
    id: uint32
    candidate: uint32
    start: Point
    end: Point
    samples: uint32
    recording: str

@dataclass
class MissionStatus(IdlStruct, typename="crackbot_msgs::msg::dds_::MissionStatus_"):
    header: Header
    stage: str
    detail: str

@dataclass
class Candidate(IdlStruct, typename="crackbot_msgs::msg::dds_::Candidate_"):
    id: uint32
    centre: Point
    axis_deg: float64
    length_mm: float64
    width_mm: float64
    score: float32

@dataclass
class Crack(IdlStruct, typename="crackbot_msgs::msg::dds_::Crack_"):
    candidate: uint32
    position: Point
    width_mm: float64
    width_low_mm: float64
    width_high_mm: float64
    confidence: float64

@dataclass
class MissionReport(IdlStruct, typename="crackbot_msgs::msg::dds_::MissionReport_"):
    header: Header
    mode: str
    scene: str
    candidates: sequence[Candidate]
    cracks: sequence[Crack]
    rejected: uint32
    passes: uint32
    elapsed_s: float64
    exploration_s: float64
    report_json: str
