//! The app as a station of a live robot, over real Zenoh sessions on loopback: the robot is the
//! telemetry crate's serving robot (the same `RobotService::serve` that `crackbot-robot --serve`
//! runs) in this process, with a simulated scene behind it; the app connects to it, shows it,
//! starts a mission through the confirm step with a signed command, watches it stream, and
//! sends the emergency stop.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

mod common;

use std::sync::Arc;
use std::time::Duration;

use crackbot_link::Key;
use crackbot_mission::inspect::InspectConfig;
use crackbot_operator::{Backend, OperatorApp, Pending};
use crackbot_telemetry::wire::Phase;
use crackbot_telemetry::{RobotService, ZenohOptions};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use common::step_until;
use crackbot_testkit::free_tcp_port;

fn phase(app: &OperatorApp, robot: &str) -> Option<Phase> {
    let f = app.fleet();
    let f = f.lock().unwrap();
    f.robot(robot).and_then(|r| r.phase().cloned())
}

#[test]
fn the_app_starts_watches_and_stops_a_live_robot_over_zenoh() {
    let dir = tempfile::tempdir().unwrap();
    let key_path = dir.path().join("link.key");
    std::fs::write(&key_path, format!("{}\n", "3c".repeat(32))).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&key_path, std::fs::Permissions::from_mode(0o600)).unwrap();
    }
    let key = Key::from_file(&key_path).unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_tcp_port());

    // The robot: serving, with the key.
    let robot = Arc::new(
        RobotService::open(
            "tank-1",
            &ZenohOptions {
                listen: vec![endpoint.clone()],
                ..ZenohOptions::default()
            },
            Some(&key),
            true,
        )
        .unwrap(),
    );
    let mut base = InspectConfig::new(
        crackbot_sim::Scene::load_or_default(None).unwrap(),
        dir.path().join("robot"),
    );
    base.rig.speedup = 8.0;
    let serving = {
        let robot = robot.clone();
        std::thread::spawn(move || {
            let mut results = Vec::new();
            robot.serve(&base, |_| {}, |n, r| results.push((n, r.is_ok())));
            results
        })
    };

    // The app, as a station that connects to the robot and signs with the key.
    let app = OperatorApp::new(
        Backend::live(
            ZenohOptions {
                connect: vec![endpoint],
                ..ZenohOptions::default()
            },
            Some(key_path),
            None,
        ),
        dir.path().join("exports"),
    );
    let mut h = Harness::builder()
        .with_size([1280.0, 800.0])
        .build_ui_state(|ui, app: &mut OperatorApp| app.show(ui), app);
    step_until(&mut h, "the robot, idle", Duration::from_secs(15), |a| {
        phase(a, "tank-1") == Some(Phase::Idle)
    });
    assert!(h.query_by_label_contains("tank-1").is_some(), "no tab");

    // Start goes through the confirm step, then out as a signed command.
    h.get_by_label("Start...").click();
    h.run_steps(2);
    assert!(
        matches!(h.state().pending, Some(Pending::Start { ref robot, .. }) if robot == "tank-1"),
        "{:?}; log: {:?}",
        h.state().pending,
        h.state().log
    );
    h.get_by_label("Confirm").click();
    step_until(
        &mut h,
        "the robot's mission, streaming",
        Duration::from_secs(60),
        |a| {
            // Zenoh orders messages per key, not across keys: the frame, plan and detections
            // may land after the first progress report.
            let seen = {
                let f = a.fleet();
                let f = f.lock().unwrap();
                f.robot("tank-1").is_some_and(|r| {
                    r.camera.is_some() && r.plan.is_some() && !r.detections.is_empty()
                })
            };
            seen && matches!(phase(a, "tank-1"), Some(Phase::Exploring { done, .. }) if done >= 1)
        },
    );
    assert!(h.state().log.iter().any(|l| l.contains("start accepted")));
    {
        let f = h.state().fleet();
        let f = f.lock().unwrap();
        let r = f.robot("tank-1").unwrap();
        assert!(r.camera.is_some() && r.plan.is_some() && !r.detections.is_empty());
        assert!(r.tactile.len() > 400, "{} samples", r.tactile.len());
        assert!(!r.verdicts.is_empty());
    }
    // The emergency stop reaches the robot: its mission ends, stopped.
    h.get_by_label(crackbot_operator::app::ESTOP_LABEL).click();
    step_until(
        &mut h,
        "the stopped mission",
        Duration::from_secs(15),
        |a| matches!(phase(a, "tank-1"), Some(Phase::Failed(ref why)) if why.contains("interrupted")),
    );
    step_until(&mut h, "the e-stop's answer", Duration::from_secs(5), |a| {
        a.log.iter().any(|l| l.contains("EMERGENCY STOP accepted"))
    });

    robot.shutdown();
    let results = serving.join().unwrap();
    assert_eq!(results, vec![(1, false)]);
}
