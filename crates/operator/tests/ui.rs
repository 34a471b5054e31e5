//! The app's UI logic and layout, headless with egui_kittest: queries by label, clicks, the
//! confirm step before anything moves an arm, the emergency stop, a whole simulated mission
//! streaming into the views, exports, and the replay of the mission it saved.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crackbot_operator::app::ESTOP_LABEL;
use crackbot_operator::source::LOCAL_ROBOT;
use crackbot_operator::{Backend, OperatorApp, Pending};
use crackbot_telemetry::wire::Phase;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;

use common::step_until;

fn harness(app: OperatorApp) -> Harness<'static, OperatorApp> {
    Harness::builder()
        .with_size([1280.0, 800.0])
        .build_ui_state(|ui, app: &mut OperatorApp| app.show(ui), app)
}

fn sim_app(out: &Path) -> OperatorApp {
    OperatorApp::new(
        Backend::sim(None, 8.0, out.join("missions")),
        out.to_path_buf(),
    )
}

fn stop_raised(app: &OperatorApp) -> bool {
    match &app.backend {
        Backend::Sim(s) => s.stop_raised(),
        _ => false,
    }
}

fn local_phase(app: &OperatorApp) -> Option<Phase> {
    let f = app.fleet();
    let f = f.lock().unwrap();
    f.robot(LOCAL_ROBOT).and_then(|r| r.phase().cloned())
}

#[test]
fn the_emergency_stop_is_visible_and_raises_the_missions_stop_flag() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(sim_app(dir.path()));
    h.run_steps(2);
    assert!(!stop_raised(h.state()));
    h.get_by_label(ESTOP_LABEL).click();
    h.run_steps(2);
    assert_eq!(h.state().estops, 1);
    assert!(stop_raised(h.state()));
    assert!(h.state().log.iter().any(|l| l.contains("EMERGENCY STOP")));
}

#[test]
fn start_asks_for_confirmation_and_cancel_starts_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(sim_app(dir.path()));
    h.run_steps(2);
    assert!(h.query_by_label("Confirm").is_none());
    h.get_by_label("Start...").click();
    h.run_steps(2);
    assert!(
        matches!(h.state().pending, Some(Pending::Start { ref robot, .. }) if robot == LOCAL_ROBOT)
    );
    h.get_by_label_contains("the arm will move");
    assert!(h.query_by_label("Confirm").is_some());
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().pending.is_none());
    assert!(h.query_by_label("Confirm").is_none());
    assert_eq!(h.state().starts, 0);
    assert!(local_phase(h.state()).is_none(), "nothing started");
}

#[test]
fn the_emergency_stop_works_while_the_confirm_step_is_open() {
    let dir = tempfile::tempdir().unwrap();
    let mut h = harness(sim_app(dir.path()));
    h.run_steps(2);
    h.get_by_label("Start...").click();
    h.run_steps(2);
    assert!(h.state().pending.is_some());
    // The dialog covers the window: it carries its own emergency stop.
    h.get_by_label("EMERGENCY STOP now").click();
    h.run_steps(2);
    assert_eq!(h.state().estops, 1);
    assert!(
        h.state().pending.is_none(),
        "the e-stop drops the pending start"
    );
    assert_eq!(h.state().starts, 0);
}

#[test]
fn a_replay_cannot_start_missions_and_a_missing_folder_is_reported_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let app = OperatorApp::new(
        Backend::replay(dir.path().join("nope")),
        dir.path().to_path_buf(),
    );
    let mut h = harness(app);
    step_until(&mut h, "the replay's error", Duration::from_secs(10), |a| {
        a.log.iter().any(|l| l.contains("report.json"))
    });
    h.state_mut().request_start();
    h.run_steps(2);
    assert!(h.state().pending.is_none());
    assert!(h.query_by_label("Confirm").is_none());
}

/// A saved mission written by hand: one candidate, one pass judged a crack.
fn write_mission(dir: &Path) {
    let img = image::RgbImage::from_pixel(64, 32, image::Rgb([90, 90, 90]));
    img.save(dir.join("frame.png")).unwrap();
    let mut csv = String::from("d1,d2,d3,p,direction,x_mm\n");
    for i in 0..800 {
        csv.push_str(&format!(
            "{},{},{},{},0,{:.3}\n",
            600 + i % 7,
            400,
            700,
            350 - (i / 100),
            i as f64 * 0.01
        ));
    }
    std::fs::write(dir.join("slide-001.csv"), csv).unwrap();
    let report = serde_json::json!({
        "mode": "fused", "scene": "hand-made",
        "cracks": [], "rejected": [],
        "candidates": [{"id": 1, "centre_mm": [100.0, 50.0], "axis_deg": 30.0, "length_mm": 40.0, "width_mm": null, "score": 0.9}],
        "passes": [{"id": 1, "candidate": 1, "start_mm": [95.0, 45.0], "end_mm": [105.0, 55.0], "samples": 800,
                    "class": "crack", "confidence": 0.87, "width_mm": 1.5, "doubt": null,
                    "dip": {"centre_mm": 7.0, "width_mm": 1.2, "confidence": 0.8},
                    "recording": "/elsewhere/slide-001.csv", "attempts": 1}],
        "plan": {"workspace": {"x_min_mm": 0.0, "x_max_mm": 200.0, "y_min_mm": 0.0, "y_max_mm": 100.0},
                 "slides": [{"candidates": [1], "start_mm": [95.0, 45.0], "end_mm": [105.0, 55.0], "passes": 2, "speed_mm_s": 4.6}],
                 "estimated_s": 12.5},
        "elapsed_s": 3.0, "out_dir": dir.display().to_string()
    });
    std::fs::write(
        dir.join("report.json"),
        serde_json::to_string(&report).unwrap(),
    )
    .unwrap();
}

fn wait_for_file(path: &Path) -> String {
    let t = Instant::now();
    loop {
        if let Ok(s) = std::fs::read_to_string(path) {
            return s;
        }
        assert!(
            t.elapsed() < Duration::from_secs(10),
            "{} not written",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_replay_shows_the_saved_candidates_verdicts_and_signals_and_exports_them() {
    let dir = tempfile::tempdir().unwrap();
    let mission = dir.path().join("m1");
    std::fs::create_dir(&mission).unwrap();
    write_mission(&mission);
    let out = dir.path().join("exports");
    let mut app = OperatorApp::new(Backend::replay(mission.clone()), out.clone());
    app.window_s = 60.0;
    let mut h = harness(app);
    step_until(&mut h, "the replay", Duration::from_secs(10), |a| {
        a.log.iter().any(|l| l.starts_with("replayed"))
    });
    h.run_steps(3);
    // The robot tab, the candidate with its verdict, position and evidence, the verdict strip.
    h.get_by_label_contains("replay:m1");
    h.get_by_label("#1");
    h.get_by_label("(100.0, 50.0)");
    h.get_by_label("0.87");
    h.get_by_label_contains("dip at 7.0 mm (w 1.2)");
    h.get_by_label_contains("pass 1 (#1): crack 0.87");
    h.get_by_label_contains("800 samples in view");
    // Exports: the visible signals and the report.
    h.get_by_label("Export CSV").click();
    h.get_by_label("Export report").click();
    h.run_steps(2);
    step_until(&mut h, "the exports", Duration::from_secs(10), |a| {
        a.log.iter().filter(|l| l.starts_with("saved")).count() >= 2
    });
    let csv_path = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "csv"))
        .unwrap();
    let csv = wait_for_file(&csv_path);
    assert_eq!(csv.lines().count(), 801, "header + every sample in view");
    assert!(csv
        .lines()
        .nth(1)
        .unwrap()
        .starts_with("0.000000,600,400,700,350"));
    let report = wait_for_file(&out.join("report-replay_m1-1.json"));
    let v: serde_json::Value = serde_json::from_str(&report).unwrap();
    assert_eq!(v["passes"][0]["class"], "crack");
}

/// A whole simulated mission in-process: confirm, four channels streaming into the plots,
/// the emergency stop ending the next one, then a mission to the end and its replay.
#[test]
fn a_simulated_mission_streams_is_stopped_by_the_estop_and_replays() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = sim_app(dir.path());
    app.window_s = 60.0;
    let mut h = harness(app);
    h.run_steps(2);

    // 1. Start, confirm, wait for the slides: the e-stop ends the mission.
    h.get_by_label("Start...").click();
    h.run_steps(2);
    h.get_by_label("Confirm").click();
    h.run_steps(2);
    assert_eq!(h.state().starts, 1);
    step_until(&mut h, "the first slide", Duration::from_secs(240), |a| {
        matches!(local_phase(a), Some(Phase::Exploring { .. })) && {
            let f = a.fleet();
            let f = f.lock().unwrap();
            f.robot(LOCAL_ROBOT).is_some_and(|r| r.tactile.len() > 400)
        }
    });
    {
        let f = h.state().fleet();
        let f = f.lock().unwrap();
        let r = f.robot(LOCAL_ROBOT).unwrap();
        assert!(r.camera.is_some(), "the frame");
        assert!(!r.detections.is_empty(), "the candidates");
        assert!(r.plan.is_some(), "the plan");
    }
    h.get_by_label("#1");
    h.get_by_label_contains("samples in view");
    // While a stroke is under way, its running verdict is shown beside the passes judged.
    let t = Instant::now();
    while h.query_by_label_contains("so far (").is_none() {
        assert!(
            t.elapsed() < Duration::from_secs(120),
            "no running verdict shown; log: {:?}",
            h.state().log
        );
        std::thread::sleep(Duration::from_millis(10));
        h.step();
    }
    h.get_by_label(ESTOP_LABEL).click();
    h.run_steps(2);
    step_until(
        &mut h,
        "the mission to stop",
        Duration::from_secs(60),
        |a| matches!(local_phase(a), Some(Phase::Failed(_))),
    );
    let Some(Phase::Failed(why)) = local_phase(h.state()) else {
        unreachable!()
    };
    assert!(
        why.to_lowercase().contains("interrupt") || why.to_lowercase().contains("stop"),
        "{why}"
    );

    // 2. A second mission to its end.
    step_until(
        &mut h,
        "the mission thread to end",
        Duration::from_secs(30),
        |a| match &a.backend {
            Backend::Sim(s) => !s.running(),
            _ => true,
        },
    );
    h.state_mut().request_start();
    h.run_steps(2);
    h.get_by_label("Confirm").click();
    h.run_steps(2);
    // (Until mission 2's own status arrives, the fleet still shows mission 1's failure.)
    step_until(
        &mut h,
        "the second mission to finish",
        Duration::from_secs(600),
        |a| {
            let f = a.fleet();
            let f = f.lock().unwrap();
            f.robot(LOCAL_ROBOT)
                .and_then(|r| r.mission.as_ref())
                .is_some_and(|m| {
                    m.mission == 2 && matches!(m.phase, Phase::Finished | Phase::Failed(_))
                })
        },
    );
    assert_eq!(
        local_phase(h.state()),
        Some(Phase::Finished),
        "log: {:?}",
        h.state().log
    );
    let report: serde_json::Value = {
        let f = h.state().fleet();
        let f = f.lock().unwrap();
        let m = f.robot(LOCAL_ROBOT).unwrap().mission.clone().unwrap();
        serde_json::from_str(&m.report_json.unwrap()).unwrap()
    };
    let live_homography = {
        let f = h.state().fleet();
        let f = f.lock().unwrap();
        f.robot(LOCAL_ROBOT)
            .unwrap()
            .camera
            .as_ref()
            .unwrap()
            .surface_to_image
    };
    let saved = PathBuf::from(report["out_dir"].as_str().unwrap());
    let passes = report["passes"].as_array().unwrap().len();
    assert!(passes > 0);

    // 3. Its replay shows the same candidates and verdicts.
    let mut r = harness(OperatorApp::new(
        Backend::replay(saved.clone()),
        dir.path().join("replay-out"),
    ));
    step_until(&mut r, "the replay", Duration::from_secs(20), |a| {
        a.log.iter().any(|l| l.starts_with("replayed"))
    });
    r.run_steps(2);
    r.get_by_label("#1");
    let f = r.state().fleet();
    let f = f.lock().unwrap();
    let robot = f.robots().next().unwrap();
    assert_eq!(robot.verdicts.len(), passes);
    assert_eq!(robot.phase(), Some(&Phase::Finished));
    assert!(robot.tactile.len() > 100);
    // Replayed from the mission's log: the samples at the times they were logged, the last one
    // the log's last (not laid end to end from the slide recordings).
    let log = crackbot_mcap::read_log(&saved.join("mission.mcap")).unwrap();
    let rows = crackbot_mcap::tactile_rows(&log).unwrap();
    let last = robot.tactile.back().unwrap();
    assert_eq!(last.t_s, rows.last().unwrap().t_s);
    assert_eq!(last.raw, rows.last().unwrap().raw);
    // The overlay is the mission's own: the report keeps the frame's homography.
    assert_eq!(
        robot.camera.as_ref().unwrap().surface_to_image,
        live_homography
    );
    assert!(!r
        .state()
        .log
        .iter()
        .any(|l| l.contains("fits the workspace")));
}
