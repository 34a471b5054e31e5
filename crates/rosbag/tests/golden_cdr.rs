//! The CDR bytes of crackbot's ROS 2 messages against golden vectors written by an independent
//! implementation: `rosbags` 0.11.9 (pure Python), its typestore built from
//! `ros/crackbot_msgs/msg/*.msg` and ROS 2 Humble's standard messages, `serialize_cdr` (little
//! endian, with the encapsulation header). The script that printed them is in
//! `crates/rosbag/docs/ros2.md`, "Golden vectors".

use crackbot_rosbag::msgs::*;

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

fn header(sec: i32, nanosec: u32, frame: &str) -> Header {
    Header {
        stamp: Time { sec, nanosec },
        frame_id: frame.into(),
    }
}

fn point(x: f64, y: f64, z: f64) -> Point {
    Point { x, y, z }
}

#[test]
fn a_tactile_sample() {
    let s = TactileSample {
        header: header(1_765_000_000, 123_456_789, "finger"),
        d1: 650,
        d2: 430,
        d3: 1023,
        p: 512,
        slide: 3,
        along_mm: 7.25,
    };
    assert_eq!(
        hex(&to_cdr(&s).unwrap()),
        "0001000040c3336915cd5b070700000066696e67657200008a02ae01ff030002030000000000000000001d40"
    );
}

#[test]
fn a_verdict() {
    let v = Verdict {
        header: header(1, 2, "surface"),
        kind: KIND_PASS,
        stroke: 4,
        candidate: 2,
        surface: "crack".into(),
        confidence: 0.75,
        width_mm: 2.0,
        count: 875,
    };
    assert_eq!(
        hex(&to_cdr(&v).unwrap()),
        "00010000010000000200000008000000737572666163650000000000040000000200000006000000637261636b00000000000000000000000000e83f00000000000000406b030000"
    );
}

#[test]
fn a_report_with_its_candidates_and_cracks() {
    let r = MissionReport {
        header: header(5, 6, "surface"),
        mode: "fused".into(),
        scene: "default".into(),
        candidates: vec![Candidate {
            id: 1,
            centre: point(0.1, 0.05, 0.0),
            axis_deg: 8.5,
            length_mm: 58.0,
            width_mm: 7.5,
            score: 0.875,
        }],
        cracks: vec![Crack {
            candidate: 1,
            position: point(0.038, 0.0299, 0.0),
            width_mm: 1.0,
            width_low_mm: 1.0,
            width_high_mm: 10.0,
            confidence: 0.5,
        }],
        rejected: 2,
        passes: 7,
        elapsed_s: 25.5,
        exploration_s: 24.5,
        report_json: "{}".into(),
    };
    assert_eq!(
        hex(&to_cdr(&r).unwrap()),
        "0001000005000000060000000800000073757266616365000600000066757365640000000800000064656661756c74000100000001000000000000009a9999999999b93f9a9999999999a93f000000000000000000000000000021400000000000004d400000000000001e400000603f010000000100000000000000dbf97e6abc74a33f75029a081b9e9e3f0000000000000000000000000000f03f000000000000f03f0000000000002440000000000000e03f020000000700000000000000008039400000000000803840030000007b7d00"
    );
}

#[test]
fn a_transform_an_image_and_a_log_line() {
    let tf = TfMessage {
        transforms: vec![TransformStamped {
            header: header(7, 8, "surface"),
            child_frame_id: "finger".into(),
            transform: Transform {
                translation: point(0.1, 0.2, 0.003),
                rotation: IDENTITY,
            },
        }],
    };
    assert_eq!(
        hex(&to_cdr(&tf).unwrap()),
        "000100000100000007000000080000000800000073757266616365000700000066696e6765720000000000009a9999999999b93f9a9999999999c93ffa7e6abc7493683f000000000000000000000000000000000000000000000000000000000000f03f"
    );
    let image = CompressedImage {
        header: header(9, 10, "camera"),
        format: "png".into(),
        data: vec![137, 80, 78],
    };
    assert_eq!(
        hex(&to_cdr(&image).unwrap()),
        "00010000090000000a0000000700000063616d657261000004000000706e67000300000089504e"
    );
    let log = RosLog {
        stamp: Time {
            sec: 11,
            nanosec: 12,
        },
        level: 20,
        name: "crackbot".into(),
        msg: "planned: 7 slides".into(),
        file: String::new(),
        function: String::new(),
        line: 0,
    };
    assert_eq!(
        hex(&to_cdr(&log).unwrap()),
        "000100000b0000000c0000001400000009000000637261636b626f740000000012000000706c616e6e65643a203720736c696465730000000100000000000000010000000000000000000000"
    );
}

#[test]
fn definitions_carry_every_type_they_use_once() {
    let d = MsgType::MissionReport.definition();
    assert!(d.starts_with("# The mission's report"), "{d}");
    for used in [
        "MSG: std_msgs/Header\n",
        "MSG: builtin_interfaces/Time\n",
        "MSG: crackbot_msgs/Candidate\n",
        "MSG: crackbot_msgs/Crack\n",
        "MSG: geometry_msgs/Point\n",
    ] {
        assert_eq!(d.matches(used).count(), 1, "{used} in\n{d}");
    }
    assert_eq!(MsgType::TfMessage.name(), "tf2_msgs/msg/TFMessage");
    assert_eq!(
        Time::from_ns(1_765_000_000_123_456_789).nanosec,
        123_456_789
    );
}
