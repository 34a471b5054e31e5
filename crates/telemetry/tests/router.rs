//! A site's topology: a Zenoh router, and a robot and a station that are both its clients
//! (`ZenohOptions::router`), over real TCP on loopback.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crackbot_link::Key;
use crackbot_telemetry::wire::{self, Phase, Telemetry};
use crackbot_telemetry::{keys, Command, CommandReply, RobotNode, Station, ZenohOptions};
use crackbot_testkit::free_tcp_port;
use zenoh::query::ConsolidationMode;
use zenoh::Wait;

#[test]
fn a_robot_and_a_station_meet_through_a_router() {
    let endpoint = format!("tcp/127.0.0.1:{}", free_tcp_port());
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    c.insert_json5("scouting/multicast/enabled", "false")
        .unwrap();
    let _router = zenoh::open(c).wait().unwrap();

    let site = ZenohOptions {
        router: Some(endpoint),
        ..ZenohOptions::default()
    };
    let key = Key::from_bytes(&[0x42; 32]).unwrap();
    let stops = Arc::new(AtomicU32::new(0));
    let robot = {
        let stops = stops.clone();
        RobotNode::open(
            "site-robot",
            &site,
            Some(&key),
            Box::new(move |c| {
                if *c == Command::Stop {
                    stops.fetch_add(1, Ordering::SeqCst);
                }
                Ok(())
            }),
        )
        .unwrap()
    };
    robot
        .publish(Telemetry::Mission(
            crackbot_telemetry::wire::MissionStatus {
                mission: 3,
                mode: "fused".into(),
                scene: "tank wall".into(),
                phase: Phase::Exploring { done: 2, of: 5 },
                report_json: None,
            },
        ))
        .unwrap();
    // A judged pass and the running verdict of the next: a joining station catches up with
    // the verdict only (a running verdict is stale by the time anyone asks).
    robot
        .publish(Telemetry::Verdict(crackbot_telemetry::wire::PassVerdict {
            id: 2,
            candidate: Some(1),
            start_mm: [0.0, 0.0],
            end_mm: [16.0, 0.0],
            samples: 1400,
            class: Some("crack".into()),
            confidence: 0.8,
            width_mm: Some(5.0),
            doubt: None,
            dip_mm: None,
        }))
        .unwrap();
    robot
        .publish(Telemetry::Feeling(crackbot_telemetry::wire::Feeling {
            id: 3,
            class: "crack".into(),
            confidence: 0.5,
            width_mm: None,
            windows: 12,
            along_mm: 2.0,
        }))
        .unwrap();
    let station = Station::open(&site, Some(&key)).unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let seen = station.fleet().robot("site-robot").is_some_and(|r| {
            r.alive == Some(true)
                && r.health.is_some()
                && r.mission.is_some()
                && !r.verdicts.is_empty()
        });
        if seen {
            break;
        }
        assert!(Instant::now() < deadline, "the station never saw the robot");
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(
        station.fleet().robot("site-robot").unwrap().phase(),
        Some(&Phase::Exploring { done: 2, of: 5 })
    );
    // What a joining station catches up with is the robot's state reply. Asked directly: the
    // station's own view may also hold the feeling if its live sample was still on its way
    // through the router when the station subscribed, which is right, and a race to assert on.
    let caught_up = catch_up_bodies(&site, "site-robot");
    assert!(
        caught_up
            .iter()
            .any(|b| matches!(b, Telemetry::Verdict(v) if v.id == 2)),
        "the judged pass is in the catch-up: {caught_up:?}"
    );
    assert!(
        !caught_up.iter().any(|b| matches!(b, Telemetry::Feeling(_))),
        "a running verdict is not in the catch-up: {caught_up:?}"
    );
    assert_eq!(
        station
            .command("site-robot", Command::Stop, Duration::from_secs(5))
            .unwrap(),
        CommandReply::Accepted
    );
    assert_eq!(stops.load(Ordering::SeqCst), 1);
    // A robot that does not exist does not answer: a clear error, not a hang.
    let e = station
        .command("nobody", Command::Stop, Duration::from_millis(500))
        .unwrap_err();
    assert!(e.to_string().contains("nobody"), "{e}");
    drop(robot);
    let deadline = Instant::now() + Duration::from_secs(2);
    while !station
        .fleet()
        .robot("site-robot")
        .unwrap()
        .is_lost(Instant::now())
    {
        assert!(
            Instant::now() < deadline,
            "the closed robot is not shown lost"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Every message of `robot`'s state reply, asked over a plain Zenoh session of the site.
fn catch_up_bodies(site: &ZenohOptions, robot: &str) -> Vec<Telemetry> {
    let session = site.open().unwrap();
    let replies = session
        .get(keys::state_key(robot))
        .consolidation(ConsolidationMode::None)
        .timeout(Duration::from_secs(5))
        .wait()
        .unwrap();
    let mut bodies = Vec::new();
    while let Ok(reply) = replies.recv() {
        let sample = reply.result().unwrap();
        bodies.push(wire::decode(&sample.payload().to_bytes()).unwrap().body);
    }
    bodies
}
