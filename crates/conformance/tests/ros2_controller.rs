//! crackbot's controller driving a ROS 2 arm over DDS, the arm played by an independent DDS
//! implementation: Eclipse Cyclone DDS's Python binding (`scripts/dds_arm.py`), following the
//! targets with a 20 ms lag and publishing its pose. The conformance suite passes through it;
//! the target stream keeps its rate and ends within a period of a Stop; a broken pose stream
//! (NaN, another frame, silence, a flood, an arm that drifts off) is a fault that stops it; and
//! guarded touches find a plate tilted and offset by drawn amounts.

use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crackbot_conformance::{run, table, Expect, Host};
use crackbot_controller::motion::frame::SurfaceFrame;
use crackbot_controller::motion::register::frame_from_points;
use crackbot_controller::ros2::config::Ros2Config;
use crackbot_controller::ros2::{guarded_touches, Ros2Arm};
use crackbot_controller::{Limits, LinkServer, LinkSettings};
use crackbot_link::{Key, Message, Mode, Security};
use crackbot_testkit::DdsArm;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A DDS domain of this test process's own (tests run side by side).
fn domain(salt: u16) -> u16 {
    (std::process::id() % 100) as u16 * 2 + salt + 10
}

/// The Cyclone DDS arm on `domain`, running until dropped.
fn dds_arm(domain: u16, args: &[&str]) -> DdsArm {
    DdsArm::start(&repo(), domain, args)
}

/// The surface frame of these tests: the plate 0.4 m out, 0.1 m to the side, 50 mm up,
/// turned 30° about the base's z axis.
fn surface() -> SurfaceFrame {
    let h = 30f64.to_radians() / 2.0;
    SurfaceFrame {
        origin_m: [0.4, -0.1, 0.05],
        rotation_xyzw: [0.0, 0.0, h.sin(), h.cos()],
        ..SurfaceFrame::default()
    }
}

fn limits() -> Limits {
    Limits {
        min_mm: [0.0, 0.0],
        max_mm: [200.0, 100.0],
        max_travel_speed_mm_s: 100.0,
        max_slide_speed_mm_s: 4.0 * 3.89,
    }
}

fn config(domain: u16) -> Ros2Config {
    let mut c = Ros2Config::default();
    c.dds.domain_id = domain;
    c
}

/// The arm's start, `--start x,y,z` in metres: above the plate's (20, 20) mm, 10 mm up.
fn start_arg() -> String {
    let b = surface().to_base([20.0, 20.0, 10.0]);
    format!("{},{},{}", b[0], b[1], b[2])
}

/// The ROS 2 controller in this process and a host talking to it.
struct Rig {
    server: LinkServer,
    host: Host,
    _dir: tempfile::TempDir,
}

fn rig(domain: u16) -> Rig {
    let dir = tempfile::tempdir().expect("tempdir");
    let key = Key::from_bytes(b"crackbot ros2 arm test key 32 B!").expect("key");
    let arm = Ros2Arm::spawn(config(domain), limits(), surface()).expect("the ROS 2 arm");
    let cs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let hs = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let host_addr = hs.local_addr().expect("addr");
    drop(hs);
    let settings = LinkSettings::new(Security::Signed(key.clone()), dir.path().join("c.epoch"));
    let server = LinkServer::spawn(arm, settings, cs, host_addr).expect("controller");
    let link = Host::link_config(Security::Signed(key), dir.path().join("h.epoch"), 1);
    let mut host = Host::connect(host_addr, server.addr(), link).expect("host");
    host.wait_for_state(Duration::from_secs(20))
        .expect("a state: the DDS arm's pose through the controller");
    Rig {
        server,
        host,
        _dir: dir,
    }
}

#[test]
fn the_conformance_suite_passes_through_the_ros2_arm() {
    let d = domain(0);
    let _arm = dds_arm(d, &["--start", &start_arg()]);
    let mut r = rig(d);
    let results = run(&mut r.host, &Expect::default(), |c| {
        eprintln!("{}: {} ({})", c.name, c.passed, c.detail);
    })
    .expect("the suite ran");
    eprintln!("{}", table(&results));
    assert!(results.iter().all(|c| c.passed), "{}", table(&results));
    r.server.shutdown().expect("report");
}

/// `t x y z frame` lines the DDS arm wrote, as (wall-clock s, surface-frame mm).
fn targets(path: &Path) -> Vec<(f64, [f64; 3])> {
    std::fs::read_to_string(path)
        .expect("the record")
        .lines()
        .filter_map(|l| {
            let v: Vec<f64> = l
                .split(' ')
                .take(4)
                .filter_map(|t| t.parse().ok())
                .collect();
            (v.len() == 4).then(|| (v[0], surface().to_surface([v[1], v[2], v[3]])))
        })
        .collect()
}

fn wall_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .expect("clock")
        .as_secs_f64()
}

#[test]
fn targets_stream_at_the_rate_and_end_within_a_period_of_a_stop() {
    let d = domain(1);
    let dir = tempfile::tempdir().expect("tempdir");
    let record = dir.path().join("targets.txt");
    let _arm = dds_arm(
        d,
        &[
            "--start",
            &start_arg(),
            "--record",
            record.to_str().expect("utf-8"),
        ],
    );
    let mut r = rig(d);
    let h = &mut r.host;
    let go = crackbot_conformance::cases::move_to(
        [180.0, 80.0, 10.0],
        20.0,
        h.deadline(Duration::from_secs(1)),
    );
    h.send(&go).expect("move");
    h.pump(Duration::from_secs(3)).expect("pump");
    assert_eq!(h.mode(), Mode::Moving);
    let stop_at = wall_s();
    h.send(&Message::Stop).expect("stop");
    h.pump(Duration::from_millis(600)).expect("pump");
    assert_eq!(h.mode(), Mode::Stopped);
    let t = targets(&record);
    let during: Vec<f64> = t.iter().map(|x| x.0).filter(|&x| x < stop_at).collect();
    let mut gaps: Vec<f64> = during.windows(2).map(|w| (w[1] - w[0]) * 1e3).collect();
    gaps.sort_by(f64::total_cmp);
    let rate = (during.len() - 1) as f64 / (during[during.len() - 1] - during[0]);
    let p99 = gaps[(gaps.len() * 99).div_ceil(100) - 1];
    let after: Vec<&(f64, [f64; 3])> = t.iter().filter(|x| x.0 >= stop_at).collect();
    let last = after.last().map_or(0.0, |x| (x.0 - stop_at) * 1e3);
    eprintln!(
        "targets: {} at {rate:.1} Hz, p99 gap {p99:.1} ms, median {:.1} ms; after the Stop: {} target(s), the last {last:.1} ms after it (load {:?})",
        during.len(),
        gaps[gaps.len() / 2],
        after.len(),
        std::fs::read_to_string("/proc/loadavg").unwrap_or_default().trim()
    );
    assert!(rate >= 100.0, "{rate} Hz");
    assert!(p99 <= 15.0, "p99 gap {p99} ms");
    // The Stop's one hold target, published within one period (8 ms) of the stop reaching the
    // controller, plus the link's and DDS's delivery.
    assert!(after.len() <= 2, "{} targets after the stop", after.len());
    assert!(last <= 30.0, "the last target {last} ms after the Stop");
    r.server.shutdown().expect("report");
}

#[test]
fn a_broken_pose_stream_is_a_fault_that_ends_the_target_stream() {
    for (k, (fault, code)) in [
        ("--nan-after", 13),
        ("--wrong-frame-after", 13),
        ("--silent-after", 11),
        ("--flood-after", 14),
        ("--drift-after", 12),
    ]
    .into_iter()
    .enumerate()
    {
        let d = domain(40 + 2 * k as u16) % 230;
        let dir = tempfile::tempdir().expect("tempdir");
        let record = dir.path().join("targets.txt");
        let arm = dds_arm(
            d,
            &[
                "--start",
                &start_arg(),
                "--record",
                record.to_str().expect("utf-8"),
                fault,
                "1.0",
            ],
        );
        let mut r = rig(d);
        let h = &mut r.host;
        let go = crackbot_conformance::cases::move_to(
            [180.0, 80.0, 10.0],
            10.0,
            h.deadline(Duration::from_secs(1)),
        );
        h.send(&go).expect("move");
        let faulted = h
            .pump_until(Duration::from_secs(6), |h| {
                matches!(h.mode(), Mode::Fault { .. })
            })
            .expect("pump");
        assert!(faulted, "{fault}: no fault, mode {:?}", h.mode());
        assert_eq!(h.mode(), Mode::Fault { code }, "{fault}");
        let at = wall_s();
        h.pump(Duration::from_millis(500)).expect("pump");
        let late = targets(&record).iter().filter(|x| x.0 > at + 0.05).count();
        assert_eq!(late, 0, "{fault}: targets went on after the fault");
        assert!(
            targets(&record)
                .iter()
                .all(|x| x.1.iter().all(|v| v.is_finite())),
            "{fault}: a target was not finite"
        );
        // A new command is refused while the pose is broken, or runs once it is fresh again.
        r.server.shutdown().expect("report");
        drop(arm);
    }
}

#[test]
fn guarded_touches_find_a_tilted_offset_plate_within_a_fifth_of_a_millimetre_and_degree() {
    // The plate drawn from the process id: tilted up to 10° about x and y, offset up to 20 mm.
    let seed = f64::from(std::process::id() % 997) / 997.0;
    let (ax, ay) = ((seed - 0.5) * 0.35, (0.5 - (seed * 7.0).fract()) * 0.35);
    let normal = nalgebra::Vector3::new(ay.sin(), -ax.sin(), 1.0).normalize();
    let point = [0.45, 0.02 * (seed - 0.5), 0.03 + 0.04 * seed];
    let plate = format!(
        "{},{},{},{},{},{}",
        point[0], point[1], point[2], normal.x, normal.y, normal.z
    );
    let d = domain(90) % 230;
    let _arm = dds_arm(
        d,
        &[
            "--start",
            "0.45,0.0,0.15",
            "--plate",
            &plate,
            "--wrench-topic",
            "/crackbot/wrench",
        ],
    );
    let mut c = config(d);
    c.wrench.topic = "/crackbot/wrench".into();
    c.motion.travel_speed_mm_s = 100.0;
    c.motion.approach_speed_mm_s = 25.0;
    let starts = [[0.40, -0.05, 0.10], [0.50, -0.05, 0.10], [0.40, 0.05, 0.10]];
    let t = Instant::now();
    let points = guarded_touches(&c, &starts, [0.0, 0.0, -1.0]).expect("touches");
    let frame = frame_from_points(&points, [0.0, 0.0, -1.0]).expect("a frame");
    let found = nalgebra::Vector3::from(frame.normal());
    let angle = found.angle(&normal).to_degrees();
    let off = (nalgebra::Vector3::from(frame.origin_m) - nalgebra::Vector3::from(point))
        .dot(&normal)
        .abs()
        * 1e3;
    eprintln!(
        "plate tilted {:.2}°: found within {angle:.3}° and {off:.3} mm from {} touches in {:.1} s",
        normal.angle(&nalgebra::Vector3::z()).to_degrees(),
        starts.len(),
        t.elapsed().as_secs_f64()
    );
    assert!(angle < 0.2, "{angle}°");
    assert!(off < 0.2, "{off} mm");
}
