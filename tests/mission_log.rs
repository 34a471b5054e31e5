//! A mission's MCAP log (`mission.mcap`), checked by an independent reader (the Python `mcap`
//! package, `scripts/mcap_check.py`), watched live over the Foxglove WebSocket protocol
//! (`--foxglove`, a Python client: `scripts/foxglove_live_check.py`), replayed by `crackbot
//! replay`, and refused with a clear error when it is cut short or corrupt; and the same log as a
//! ROS 2 bag (`crackbot log to-ros2`), read by independent ROS 2 readers (`rosbags`,
//! `mcap-ros2-support`: `scripts/ros2_bag_check.py`).

use std::path::Path;
use std::process::{Command, Stdio};

use crackbot_tests::{binary, crackbot, text};

/// Runs `bash scripts/SCRIPT ARGS` (the venvs `scripts/setup.sh` made) and returns its exit
/// status and JSON line.
fn script_json<S: AsRef<std::ffi::OsStr>>(script: &str, args: &[S]) -> (bool, serde_json::Value) {
    let out = Command::new("bash")
        .arg(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scripts")
                .join(script),
        )
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running scripts/{script}: {e}"));
    let stdout = text(&out.stdout);
    let json = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("{e}: stdout {stdout}\nstderr {}", text(&out.stderr)));
    (out.status.success(), json)
}

/// Runs `bash scripts/mcap_check.sh ARGS`.
fn python_check(args: &[&str]) -> (bool, serde_json::Value) {
    script_json("mcap_check.sh", args)
}

/// A fused mission on the built-in default scene at 8× real time, into `dir`.
fn default_scene_mission(dir: &Path, extra: &[&str]) -> serde_json::Value {
    let out = Command::new(binary("crackbot-robot"))
        .args(["--speedup", "8", "--json", "--out"])
        .arg(dir)
        .args(extra)
        .output()
        .expect("running crackbot-robot");
    assert!(out.status.success(), "{}", text(&out.stderr));
    serde_json::from_str(&text(&out.stdout)).expect("the report")
}

#[test]
fn a_default_scene_mission_writes_an_mcap_the_python_reader_validates() {
    let dir = tempfile::tempdir().unwrap();
    let report = default_scene_mission(dir.path(), &[]);
    let (ok, check) = python_check(&[dir.path().to_str().unwrap(), "--json"]);
    assert!(ok, "{check}");
    let channels = check["channels"].as_object().unwrap();
    for topic in [
        "/camera/image",
        "/camera/detections",
        "/plan",
        "/tf",
        "/log",
        "/tactile",
        "/slide",
        "/arm/pose",
        "/verdicts",
        "/feeling",
        "/health",
        "/mission/status",
        "/mission/report",
    ] {
        assert!(
            channels.get(topic).is_some_and(|n| n.as_u64() > Some(0)),
            "{topic}: {check}"
        );
    }
    let passes = report["passes"].as_array().unwrap();
    assert!(!passes.is_empty());
    assert_eq!(channels["/verdicts"].as_u64(), Some(passes.len() as u64));
    let judged: u64 = passes.iter().map(|p| p["samples"].as_u64().unwrap()).sum();
    assert_eq!(channels["/slide"].as_u64(), Some(judged));

    // The robot's own reader agrees, and `crackbot replay` takes the log.
    let log = crackbot_mcap::read_log(&dir.path().join("mission.mcap")).unwrap();
    let rows = crackbot_mcap::tactile_rows(&log).unwrap();
    assert_eq!(rows.len() as u64, channels["/tactile"].as_u64().unwrap());
    assert!(rows
        .windows(2)
        .all(|w| w[0].log_time_ns <= w[1].log_time_ns));
    let file = dir.path().join("mission.mcap");
    let out = crackbot(&["replay", file.to_str().unwrap(), "--unpaced", "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let replay: serde_json::Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    assert_eq!(
        replay["samples"].as_u64(),
        Some(rows.len() as u64),
        "{replay}"
    );
}

/// Runs `bash scripts/ros2_bag_check.sh BAG MISSION --json`.
fn ros2_check(bag: &Path, mission: &Path) -> (bool, serde_json::Value) {
    script_json(
        "ros2_bag_check.sh",
        &[bag.as_os_str(), mission.as_os_str(), "--json".as_ref()],
    )
}

#[test]
fn a_default_scene_mission_becomes_a_ros2_bag_that_independent_readers_read_whole() {
    let dir = tempfile::tempdir().unwrap();
    let report = default_scene_mission(dir.path(), &[]);
    let mission = dir.path().to_str().unwrap();
    let out = crackbot(&["log", "to-ros2", mission, "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let bag: serde_json::Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    let bag_dir = dir.path().join("ros2");
    assert_eq!(bag["bag"].as_str(), bag_dir.to_str());
    let (ok, check) = ros2_check(&bag_dir, dir.path());
    assert!(ok, "{check}");
    assert_eq!(check["rosbags_errors"], 0, "{check}");
    assert_eq!(check["mcap_ros2_errors"], 0, "{check}");
    // The counts the readers found are the writer's, and the report's.
    assert_eq!(check["topics"], bag["topics"], "{check}");
    let topics = &check["topics"];
    let passes = report["passes"].as_array().unwrap().len() as u64;
    assert!(passes > 0);
    assert_eq!(topics["/crackbot/verdicts"].as_u64(), Some(passes));
    assert_eq!(topics["/crackbot/strokes"].as_u64(), Some(passes));
    assert_eq!(topics["/crackbot/mission/report"].as_u64(), Some(1));
    assert_eq!(
        topics["/tf"], topics["/crackbot/arm/pose"],
        "one transform per pose"
    );
    assert!(check["sliding_samples_with_position"].as_u64() > Some(0));
    // The bag costs no more bytes than the log it came from (the bound: 1.5×).
    let size = |p: &Path| std::fs::metadata(p).unwrap().len() as f64;
    let mcap = std::path::PathBuf::from(bag["mcap"].as_str().unwrap());
    let ratio = size(&mcap) / size(&dir.path().join("mission.mcap"));
    assert!(ratio <= 1.5, "the bag is {ratio:.2}× the log");
    // A bag is a folder of its own: writing it again is refused, naming the folder.
    let again = crackbot(&["log", "to-ros2", mission]);
    assert!(!again.status.success());
    assert!(
        text(&again.stderr).contains("already exists"),
        "{}",
        text(&again.stderr)
    );
}

/// `scripts/ros2_live_check.sh` subscribed on DDS domain `domain` (Cyclone DDS), once READY.
fn live_subscriber(domain: u16, late_s: f64) -> std::process::Child {
    use std::io::BufRead;
    let mut child = Command::new("bash")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/ros2_live_check.sh"))
        .args([
            "--domain",
            &domain.to_string(),
            "--late",
            &late_s.to_string(),
        ])
        .args(["--timeout", "120"])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("starting scripts/ros2_live_check.sh (bash scripts/setup.sh)");
    let mut line = String::new();
    let stdout = child.stdout.as_mut().expect("stdout");
    std::io::BufReader::new(stdout)
        .read_line(&mut line)
        .expect("READY");
    assert_eq!(line.trim(), "READY", "the subscriber did not start");
    child
}

#[test]
fn a_mission_at_twice_real_time_is_received_live_over_dds_by_cyclone() {
    let dir = tempfile::tempdir().unwrap();
    let domain = 90 + (std::process::id() % 50) as u16;
    // A second set of readers joins 4 s in, mid-mission.
    let sub = live_subscriber(domain, 4.0);
    let out = Command::new(binary("crackbot-robot"))
        .args([
            "--speedup",
            "2",
            "--json",
            "--ros2",
            &domain.to_string(),
            "--out",
        ])
        .arg(dir.path())
        .output()
        .expect("running crackbot-robot");
    assert!(out.status.success(), "{}", text(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&text(&out.stdout)).unwrap();
    let got = sub.wait_with_output().expect("the subscriber's output");
    let got: serde_json::Value = serde_json::from_str(text(&got.stdout).trim())
        .unwrap_or_else(|e| panic!("{e}: {}", text(&got.stdout)));
    // Every sample the log holds, against those received (best effort, loopback).
    let log = crackbot_mcap::read_log(&dir.path().join("mission.mcap")).unwrap();
    let sent = crackbot_mcap::tactile_rows(&log).unwrap().len() as f64;
    let received = got["tactile"].as_f64().unwrap();
    assert!(
        received >= 0.99 * sent && received <= sent,
        "{received} of {sent} samples: {got}"
    );
    assert_eq!(got["tactile_stamps_monotonic"], true, "{got}");
    // Every verdict and stroke, in order; the report whole.
    let ids: Vec<u64> = report["passes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["id"].as_u64().unwrap())
        .collect();
    assert!(!ids.is_empty());
    let as_ids = |v: &serde_json::Value| -> Vec<u64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect()
    };
    assert_eq!(as_ids(&got["verdicts"]), ids, "{got}");
    assert_eq!(as_ids(&got["strokes"]), ids, "{got}");
    assert_eq!(got["report"]["json"], report, "the report as report.json");
    assert_eq!(
        got["stages"].as_array().unwrap().last(),
        Some(&serde_json::json!("finished"))
    );
    // The late joiner: the last status published before it joined, then the report, and
    // every verdict (transient local).
    let late = &got["late"];
    let first = &late["first_status"];
    assert!(
        first["stamp_ns"].as_u64() < late["joined_ns"].as_u64(),
        "a status from before it joined: {late}"
    );
    assert_eq!(late["report"], true, "{late}");
    assert_eq!(as_ids(&late["verdicts"]), ids, "{late}");
}

#[test]
fn a_log_that_is_not_one_is_refused_by_the_bag_writer_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("mission.mcap");
    std::fs::write(&fake, b"not an mcap file at all").unwrap();
    let out = crackbot(&["log", "to-ros2", fake.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("mission.mcap"), "{err}");
    assert!(!dir.path().join("ros2").exists(), "no bag begun: {err}");
}

#[test]
fn a_log_cut_short_or_corrupt_is_refused_by_replay_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    default_scene_mission(dir.path(), &["--mode", "vision"]);
    let whole = std::fs::read(dir.path().join("mission.mcap")).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &whole[..whole.len() * 2 / 3]).unwrap();
    let garbage = dir.path().join("garbage.mcap");
    std::fs::write(&garbage, b"\x89MCAP0\r\nnot really").unwrap();
    for file in [&cut, &garbage] {
        let out = crackbot(&["replay", file.to_str().unwrap(), "--unpaced"]);
        let err = text(&out.stderr);
        assert!(!out.status.success());
        assert!(err.contains("not a complete MCAP file"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // And the independent reader fails on the cut file too.
    std::fs::rename(&cut, dir.path().join("mission.mcap")).unwrap();
    let (ok, check) = python_check(&[dir.path().to_str().unwrap(), "--json"]);
    assert!(!ok, "{check}");
}

#[test]
fn no_mcap_writes_no_log() {
    let dir = tempfile::tempdir().unwrap();
    default_scene_mission(dir.path(), &["--mode", "vision", "--no-mcap"]);
    assert!(dir.path().join("report.json").is_file());
    assert!(!dir.path().join("mission.mcap").exists());
}

#[test]
fn a_mission_is_watched_live_over_the_foxglove_websocket_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let port = crackbot_testkit::free_tcp_port();
    let addr = format!("127.0.0.1:{port}");
    let mut robot = Command::new(binary("crackbot-robot"))
        .args(["--speedup", "2", "--json", "--foxglove", &addr, "--out"])
        .arg(dir.path())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawning crackbot-robot");
    let url = format!("ws://{addr}");
    let (ok, live) = python_check(&["--live", &url, "--seconds", "120", "--until-verdicts", "2"]);
    let status = robot.wait().unwrap();
    assert!(ok, "{live}");
    assert!(status.success());
    assert_eq!(
        live["advertised"]["/tactile"], "crackbot.TactileSample",
        "{live}"
    );
    assert_eq!(
        live["advertised"]["/camera/image"], "foxglove.CompressedImage",
        "{live}"
    );
    let received = &live["received"];
    assert!(received["/tactile"].as_u64() > Some(100), "{live}");
    assert!(received["/verdicts"].as_u64() >= Some(2), "{live}");
    let first = &live["first"]["/tactile"]["message"];
    for k in ["d1", "d2", "d3", "p"] {
        assert!(first[k].as_u64().is_some_and(|c| c < 1024), "{live}");
    }
}
