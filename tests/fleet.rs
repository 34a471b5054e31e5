//! Fleet telemetry over real Zenoh sessions on loopback: two robot processes
//! (`crackbot-robot --telemetry`) and stations in this process. A station joining mid-mission
//! catches up; signed commands are obeyed, unsigned, wrongly signed and replayed ones refused;
//! a robot that dies is shown as lost within 2 s.

use std::process::{Child, Command as Process, Stdio};
use std::time::{Duration, Instant};

use crackbot_link::Key;
use crackbot_telemetry::wire::Phase;
use crackbot_telemetry::{Command, CommandReply, Fleet, Station, ZenohOptions};
use crackbot_testkit::free_tcp_port;
use crackbot_tests::binary;

/// Writes a key file of `byte` repeated (hex), mode 0600.
fn key_file(path: &std::path::Path, byte: &str) -> Key {
    std::fs::write(path, format!("{}\n", byte.repeat(32))).expect("key");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    }
    Key::from_file(path).expect("key file")
}

struct Robot {
    child: Child,
    endpoint: String,
}

impl Robot {
    fn spawn(name: &str, out: &std::path::Path, extra: &[&str]) -> Robot {
        let endpoint = format!("tcp/127.0.0.1:{}", free_tcp_port());
        let child = Process::new(binary("crackbot-robot"))
            .args(["--telemetry", name, "--zenoh-listen", &endpoint, "--json"])
            .arg("--out")
            .arg(out)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawning crackbot-robot");
        Robot { child, endpoint }
    }
}

impl Drop for Robot {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn station(robots: &[&Robot], key: Option<&Key>) -> Station {
    let options = ZenohOptions {
        connect: robots.iter().map(|r| r.endpoint.clone()).collect(),
        ..ZenohOptions::default()
    };
    Station::open(&options, key).expect("station")
}

/// Waits up to `timeout` until `check` holds on the station's fleet; panics with `what` and the
/// fleet's state otherwise.
fn wait_for(s: &Station, what: &str, timeout: Duration, check: impl Fn(&Fleet) -> bool) {
    let deadline = Instant::now() + timeout;
    loop {
        if check(&s.fleet()) {
            return;
        }
        if Instant::now() > deadline {
            let f = s.fleet();
            let state: Vec<_> = f
                .robots()
                .map(|r| (r.name.clone(), r.alive, r.phase().cloned(), r.received))
                .collect();
            panic!("{what}: not within {timeout:?}; fleet: {state:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn phase(f: &Fleet, robot: &str) -> Option<Phase> {
    f.robot(robot).and_then(|r| r.phase().cloned())
}

#[test]
#[expect(
    clippy::too_many_lines,
    reason = "one scenario test that reads top to bottom"
)]
fn two_robots_and_stations_watch_command_and_lose_them_over_zenoh() {
    let dir = tempfile::tempdir().unwrap();
    let key = key_file(&dir.path().join("fleet.key"), "5a");
    let wrong = key_file(&dir.path().join("wrong.key"), "a5");
    let key_path = dir.path().join("fleet.key");
    // r1 serves: it waits for missions that stations start. r2 runs a fused mission on the
    // default scene at once, in real time (long enough to join it halfway).
    let r1 = Robot::spawn(
        "r1",
        &dir.path().join("r1"),
        &[
            "--serve",
            "--command-key",
            key_path.to_str().unwrap(),
            "--speedup",
            "4",
        ],
    );
    let mut r2 = Robot::spawn(
        "r2",
        &dir.path().join("r2"),
        &["--command-key", key_path.to_str().unwrap()],
    );

    // A station that watches from the start, without the key.
    let watcher = station(&[&r1, &r2], None);
    wait_for(
        &watcher,
        "both robots alive, r1 idle, r2 sliding",
        Duration::from_secs(90),
        |f| {
            f.robots().filter(|r| r.alive == Some(true)).count() == 2
                && phase(f, "r1") == Some(Phase::Idle)
                && matches!(phase(f, "r2"), Some(Phase::Exploring { done, .. }) if done >= 1)
        },
    );
    {
        let f = watcher.fleet();
        let r2v = f.robot("r2").unwrap();
        assert!(r2v.tactile_total > 400, "{} samples", r2v.tactile_total);
        let h = r2v.health.unwrap();
        let stream = h.stream.expect("r2's stream health");
        assert!(stream.sample_rate_hz > 300.0, "{stream:?}");
        assert_eq!(stream.crc_errors, 0);
        assert!(f.robot("r1").unwrap().health.unwrap().stream.is_none());
    }

    // A second station joins mid-mission and catches up at once: the frame (published once,
    // before it joined), the candidates, the plan and the verdicts so far.
    let operator = station(&[&r1, &r2], Some(&key));
    wait_for(
        &operator,
        "the joining station catching up by itself",
        Duration::from_secs(3),
        |f| {
            f.robot("r2")
                .is_some_and(|r| r.camera.is_some() && r.plan.is_some())
        },
    );
    let n = operator.catch_up(Duration::from_secs(3)).unwrap();
    assert!(n >= 4, "{n} state samples");
    {
        let f = operator.fleet();
        let r2v = f.robot("r2").expect("r2 after catching up");
        assert!(
            matches!(r2v.phase(), Some(Phase::Exploring { .. })),
            "{:?}",
            r2v.phase()
        );
        let frame = r2v
            .camera
            .as_ref()
            .expect("the frame, from the state query");
        let img = image::load_from_memory(&frame.png).unwrap();
        assert_eq!((img.width(), img.height()), (frame.width, frame.height));
        assert!(!r2v.detections.is_empty());
        let plan = r2v.plan.as_ref().expect("the plan");
        assert!(!plan.slides.is_empty());
        assert!(!r2v.verdicts.is_empty(), "no verdict so far");
        assert_eq!(phase(&f, "r1"), Some(Phase::Idle));
    }

    // Commands. Without the key: refused, except the emergency stop.
    let reply = |s: &Station, robot: &str, c: Command| {
        s.command(robot, c, Duration::from_secs(5))
            .expect("an answer")
    };
    let start = Command::Start {
        mode: "vision".into(),
        scene_toml: None,
    };
    match reply(&watcher, "r1", start.clone()) {
        CommandReply::Refused(why) => assert!(why.contains("unsigned"), "{why}"),
        r => panic!("an unsigned start was {r:?}"),
    }
    assert_eq!(
        reply(&watcher, "r1", Command::EmergencyStop),
        CommandReply::Accepted
    );
    // With another key: refused.
    let intruder = station(&[&r1], Some(&wrong));
    match reply(&intruder, "r1", start.clone()) {
        CommandReply::Refused(why) => assert!(why.contains("signature"), "{why}"),
        r => panic!("a wrongly signed start was {r:?}"),
    }
    // r2 runs its command line's mission: it refuses to start another.
    match reply(&operator, "r2", start.clone()) {
        CommandReply::Refused(why) => assert!(why.contains("--serve"), "{why}"),
        r => panic!("{r:?}"),
    }
    // Signed: r1 runs a vision mission and publishes its report.
    assert_eq!(reply(&operator, "r1", start), CommandReply::Accepted);
    wait_for(
        &operator,
        "r1's vision mission finished",
        Duration::from_secs(60),
        |f| phase(f, "r1") == Some(Phase::Finished),
    );
    {
        let f = operator.fleet();
        let m = f.robot("r1").unwrap().mission.clone().unwrap();
        assert_eq!((m.mission, m.mode.as_str()), (1, "vision"));
        let report: serde_json::Value =
            serde_json::from_str(m.report_json.as_deref().expect("the report")).unwrap();
        assert!(report["cracks"].as_array().is_some_and(|c| !c.is_empty()));
    }
    // A recorded signed stop replayed: a stop always runs (issue 57; other commands' replays
    // are refused, `crackbot_telemetry::command` tests)…
    let recorded = operator.sign("r1", Command::Stop);
    let send = |p: &Vec<u8>| {
        operator
            .send_raw("r1", p.clone(), Duration::from_secs(5))
            .unwrap()
    };
    assert_eq!(send(&recorded), CommandReply::Accepted);
    assert_eq!(send(&recorded), CommandReply::Accepted);
    // …and replayed to the other robot: refused there too.
    match operator
        .send_raw("r2", recorded, Duration::from_secs(5))
        .unwrap()
    {
        CommandReply::Refused(why) => assert!(why.contains("r1"), "{why}"),
        r => panic!("{r:?}"),
    }

    // r2 dies mid-mission: both stations show it lost within 2 s; r1 stays.
    assert!(matches!(
        phase(&watcher.fleet(), "r2"),
        Some(Phase::Exploring { .. })
    ));
    r2.child.kill().unwrap();
    let killed = Instant::now();
    wait_for(&watcher, "r2 lost", Duration::from_secs(2), |f| {
        f.robot("r2").unwrap().is_lost(Instant::now())
    });
    let lost_after = killed.elapsed();
    println!("r2 shown as lost {lost_after:?} after it was killed");
    wait_for(
        &operator,
        "r2 lost (operator)",
        Duration::from_secs(2),
        |f| f.robot("r2").unwrap().is_lost(Instant::now()),
    );
    assert!(!watcher.fleet().robot("r1").unwrap().is_lost(Instant::now()));

    // r1 hangs (SIGSTOP: its TCP links stay open, its token stays declared, its heartbeat
    // stops): shown as lost within 2 s all the same; back when it resumes.
    let pid = r1.child.id().to_string();
    let signal = |sig: &str| {
        assert!(Process::new("kill")
            .args([sig, &pid])
            .status()
            .unwrap()
            .success());
    };
    signal("-STOP");
    let hung = Instant::now();
    wait_for(&watcher, "hung r1 lost", Duration::from_secs(2), |f| {
        f.robot("r1").unwrap().is_lost(Instant::now())
    });
    println!(
        "hung r1 shown as lost {:?} after it stopped",
        hung.elapsed()
    );
    signal("-CONT");
    wait_for(&watcher, "r1 back", Duration::from_secs(3), |f| {
        !f.robot("r1").unwrap().is_lost(Instant::now())
    });

    // Ctrl-C ends the serving robot cleanly.
    let status = Process::new("kill").args(["-INT", &pid]).status().unwrap();
    assert!(status.success());
    let mut r1 = r1;
    let deadline = Instant::now() + Duration::from_secs(10);
    let code = loop {
        if let Some(s) = r1.child.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < deadline, "r1 did not end on Ctrl-C");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(code.success(), "r1 ended with {code:?}");
}

#[test]
fn bad_fleet_settings_are_named_before_the_robot_starts() {
    let dir = tempfile::tempdir().unwrap();
    let fails_saying = |args: &[&str], says: &str| {
        let out = Process::new(binary("crackbot-robot"))
            .args(args)
            .arg("--out")
            .arg(dir.path())
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{args:?}: {err}");
    };
    let listen = ["--zenoh-listen", "tcp/127.0.0.1:1"];
    fails_saying(&[&["--telemetry", "bad/name"][..], &listen].concat(), "'/'");
    fails_saying(
        &["--telemetry", "r9", "--zenoh-connect", "127.0.0.1"],
        "tcp/HOST:PORT",
    );
    // --serve without --telemetry is a usage error.
    fails_saying(&["--serve"], "--telemetry");
}
