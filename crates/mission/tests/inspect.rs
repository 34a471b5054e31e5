//! Whole missions over real sockets: the simulated controller over authenticated UDP on loopback,
//! the firmware writing into a real pseudo-terminal, the deployed tactile models and the ONNX
//! detector; with the faults the robot must survive injected.
#![expect(
    clippy::unwrap_used,
    clippy::result_large_err,
    reason = "a test stops at the first thing it did not expect; the missions' own error is returned as it is"
)]

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crackbot_controller::SensorStall;
use crackbot_link::FaultConfig;
use crackbot_mission::inspect::{run_inspection, InspectConfig, InspectMode, InspectReport};
use crackbot_mission::MissionError;
use crackbot_sim::Scene;

/// One 10 mm crack across the plate's middle, the default scene's camera and arm.
fn one_crack() -> Scene {
    Scene::from_toml_str(
        r#"
name = "one 10 mm crack"
[plate]
size_mm = [200.0, 100.0]
[[features]]
kind = "crack"
path = [[85.0, 35.0], [120.0, 62.0]]
width_mm = 10.0
depth_mm = 4.0
edge_radius_mm = 0.5
[camera]
resolution = [640, 480]
focal_px = [700.0, 700.0]
position_mm = [100.0, 50.0, 250.0]
look_at_mm = [100.0, 50.0]
noise_sigma = 2.0
lighting_variation = 0.15
"#,
        "<test>",
    )
    .unwrap()
}

/// One mission at a time: they run faster than real time, and two at once on a 2-core machine
/// would make each other's sensor look stalled.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn mission(config: &InspectConfig) -> Result<InspectReport, MissionError> {
    let _one = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let stop = AtomicBool::new(false);
    run_inspection(&config.check()?, &stop, |_| {})
}

/// A fused mission over `scene` at speed-up 8 with the default settings; its recordings go to
/// a temporary folder that is gone afterwards.
fn fast_mission(scene: &Scene) -> InspectReport {
    let dir = tempfile::tempdir().unwrap();
    fast_mission_in(scene, dir.path())
}

/// [`fast_mission`] with its recordings kept in `dir`.
fn fast_mission_in(scene: &Scene, dir: &std::path::Path) -> InspectReport {
    let mut c = InspectConfig::new(scene.clone(), dir);
    c.rig.speedup = 8.0;
    mission(&c).expect("mission")
}

/// The same with the from-scratch detector (`models/detector/crack-detector-320.onnx`, the
/// default until 2026-12-08): it takes the screw heads of the scenes below for cracks, which the
/// fine-tuned default does not, and these tests are about what the finger does with such a
/// candidate.
fn fast_mission_scratch_eye(scene: &Scene, dir: &std::path::Path) -> InspectReport {
    let mut c = InspectConfig::new(scene.clone(), dir);
    c.rig.speedup = 8.0;
    c.perceive.detector_model = Some(crackbot_datasets::model_path(
        "detector/crack-detector-320.onnx",
    ));
    mission(&c).expect("mission")
}

/// Trial scene `seed` with the authors' printed crack profile.
fn trial_scene(seed: u64) -> Scene {
    use crackbot_research::{as_printed, trial_params};
    as_printed(&crackbot_sim::random_scene(&trial_params(), seed).unwrap())
}

/// Trial scene `seed` with the authors' printed crack profile, and the path of its first line
/// under 1 mm wide: a crack where `crack`, else a printed decoy.
fn trial_scene_and_thin_line(seed: u64, crack: bool) -> (Scene, Vec<[f64; 2]>) {
    use crackbot_sim::Feature;
    let scene = trial_scene(seed);
    let path = scene
        .features
        .iter()
        .find_map(|f| match f {
            Feature::Crack { path, width_mm, .. } if crack && *width_mm < 1.0 => Some(path),
            Feature::Decoy { path, width_mm, .. } if !crack && *width_mm < 1.0 => Some(path),
            _ => None,
        })
        .unwrap_or_else(|| panic!("trial scene {seed} has no line under 1 mm of that kind"))
        .clone();
    (scene, path)
}

/// The report's crack where `on_it`, its print check's ratio on the crack's side of the
/// threshold; panics naming the rejected candidates where there is none.
fn reported_as_a_crack(
    r: &InspectReport,
    on_it: impl Fn([f64; 2]) -> bool,
) -> &crackbot_mission::inspect::ReportedCrack {
    let crack = r
        .cracks
        .iter()
        .find(|k| on_it(k.position_mm))
        .unwrap_or_else(|| panic!("the crack is not reported: {:#?}", r.rejected));
    let ratio = crack.evidence.height_ratio;
    assert!(
        ratio.is_some_and(|h| h < crackbot_tactile::print_check::PRINT_RATIO),
        "{:?}",
        crack.evidence
    );
    crack
}

/// Trial scene `seed` with the authors' printed crack profile, and the path of its feature
/// `index`, which must be a crack.
fn trial_scene_and_crack(seed: u64, index: usize) -> (Scene, Vec<[f64; 2]>) {
    let scene = trial_scene(seed);
    let path = match &scene.features[index] {
        crackbot_sim::Feature::Crack { path, .. } => path.clone(),
        f => panic!("trial scene {seed}'s feature {index} is not a crack: {f:?}"),
    };
    (scene, path)
}

fn config(dir: &std::path::Path) -> InspectConfig {
    let mut c = InspectConfig::new(one_crack(), dir);
    c.rig.speedup = 8.0;
    c.plan.planner.passes = 2;
    c
}

/// Passes judged: all but those left unjudged because their stroke's ends read unlike each
/// other (the candidate was stroked again beside them), each of which has its doubt say so.
fn judged(passes: &[crackbot_mission::inspect::PassRecord]) -> usize {
    let unjudged = |p: &&crackbot_mission::inspect::PassRecord| {
        matches!(
            p.doubt,
            Some(crackbot_mission::inspect::PassDoubt::NotJudged { .. })
        )
    };
    for p in passes.iter().filter(unjudged) {
        assert_eq!(p.class, None, "{p:?}");
    }
    passes.len() - passes.iter().filter(unjudged).count()
}

/// The crack's crossing of the slide, against the scene's truth: distance from the crack's
/// centre line.
fn distance_to_crack(p: [f64; 2]) -> f64 {
    let (a, b) = ([85.0, 35.0], [120.0, 62.0]);
    let d: [f64; 2] = [b[0] - a[0], b[1] - a[1]];
    let l = d[0].hypot(d[1]);
    ((p[0] - a[0]) * d[1] - (p[1] - a[1]) * d[0]).abs() / l
}

#[test]
fn a_fused_mission_finds_the_crack_with_synchronised_positions_and_saves_everything() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    // The controller's clock 3.2 s ahead and 150 ppm fast: the robot synchronises to it.
    c.rig.clock.offset_us = 3.2e6;
    c.rig.clock.drift_ppm = 150.0;
    let r = mission(&c).unwrap();
    println!("{}", serde_json::to_string_pretty(&r.cracks).unwrap());
    println!("{}", serde_json::to_string_pretty(&r.candidates).unwrap());
    for p in &r.passes {
        println!("pass {} {:?} -> {:?}", p.id, p.start_mm, p.end_mm);
    }
    assert_eq!(r.mode, InspectMode::Fused);
    assert!(!r.candidates.is_empty(), "the detector found nothing");
    // Two judged passes per candidate; the finger can jam in the 10 mm crack (its strokes' ends
    // then read unlike each other), and the candidate is then stroked again beside the first
    // line, the first passes kept but not judged.
    assert_eq!(judged(&r.passes), 2 * r.candidates.len());
    for p in &r.passes {
        assert!(p.samples > 1000, "pass {} has {} samples", p.id, p.samples);
        assert!(std::path::Path::new(&p.recording).is_file());
    }
    assert!(dir.path().join("report.json").is_file());
    assert!(dir.path().join("frame.png").is_file());
    // The controller's clock fit: 150 ppm fast → the host runs −150 ppm against it.
    let fit = r.controller_clock.unwrap();
    // (A few seconds of 100 Hz states bound the rate only as well as the fastest messages at
    // the window's two ends: on a loaded 2-core CI machine 1 ms of queueing at each end of
    // 2.6 s is 770 ppm, and a run saw the fit 437 ppm off. So the bound is 2 ms over the
    // window's span, and never under 400 ppm; crate::sync's tests check the estimator over
    // longer runs.)
    let span_s = fit.points as f64 / 100.0;
    let bound_ppm = (2e-3 / span_s * 1e6).max(400.0);
    assert!(
        (fit.rate_ppm + 150.0).abs() < bound_ppm,
        "{fit:?}, bound {bound_ppm:.0} ppm"
    );
    // The fitted line lies below every (sent, received) point, so its offset is only as tight as
    // the fastest message in the window. On a loaded 2-core CI machine every state of a stretch
    // can wait tens of ms for the robot's thread (a run saw the fit 76 ms off); 0.2 s is 0.9 mm at
    // the slide speed, and the dip check below bounds what that costs the localisation.
    assert!((fit.offset_us + 3.2e6).abs() < 2e5, "{fit:?}");
    // Every pass's dip (where the proximity channel sees the crack) touches the crack's span:
    // within its half width (5 mm) and a millimetre of the centre line. The simulated dip covers
    // the near part of a wide crack only (crackbot_tactile::localise, "Measured accuracy"), so
    // each pass's dip lies 3–5.5 mm from the line on the side the finger enters from. (A clock
    // offset left uncorrected would put it 15 mm away: 3.2 s at 4.6 mm/s.)
    let mut dips = 0;
    for p in &r.passes {
        if let Some(d) = p.dip {
            let u = [p.end_mm[0] - p.start_mm[0], p.end_mm[1] - p.start_mm[1]];
            let l = u[0].hypot(u[1]);
            let at = [
                p.start_mm[0] + d.centre_mm * u[0] / l,
                p.start_mm[1] + d.centre_mm * u[1] / l,
            ];
            let err = distance_to_crack(at);
            println!(
                "pass {} dip at {at:?}: {err:.2} mm from the crack's centre line",
                p.id
            );
            assert!(err < 6.0, "pass {}: {err} mm", p.id);
            dips += 1;
        }
    }
    assert!(dips >= 1, "no pass located the crack");
    let pieces: usize = r.cracks.iter().map(|c| c.evidence.pieces.len()).sum();
    assert_eq!(
        r.cracks.len() + pieces + r.rejected.len(),
        r.candidates.len()
    );
}

#[test]
fn lost_reordered_and_duplicated_packets_are_survived() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    let faults = FaultConfig {
        drop: 0.1,
        reorder: 0.05,
        duplicate: 0.05,
        ..FaultConfig::default()
    };
    c.rig.faults.link = Some(faults.clone());
    c.rig.host_link_faults = Some(FaultConfig { seed: 9, ..faults });
    c.plan.planner.passes = 4;
    let r = mission(&c).unwrap();
    assert_eq!(judged(&r.passes), 4 * r.candidates.len());
    // The faults were met (retries, refused duplicates and stale copies) and survived.
    assert!(
        r.link.retries + r.link.rejected + r.link.duplicates > 0,
        "no fault seen: {:?}",
        r.link
    );
    for p in &r.passes {
        assert!(p.samples > 1000, "pass {}: {} samples", p.id, p.samples);
    }
}

#[test]
fn a_stalled_sensor_stream_is_waited_for_and_the_slide_done_again() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.rig.faults.stall = Some(SensorStall {
        slide: 1,
        duration: Duration::from_secs(1),
    });
    let r = mission(&c).unwrap();
    assert_eq!(r.passes[0].attempts, 2, "{:?}", r.passes[0]);
    assert!(r.passes[0].samples > 1000);
}

#[test]
fn a_controller_restart_mid_mission_is_noticed_and_the_slide_done_again() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.rig.faults.restart_during_slide = Some(1);
    let r = mission(&c).unwrap();
    assert!(
        r.passes.iter().any(|p| p.attempts == 2),
        "no pass was repeated: {:?}",
        r.passes.iter().map(|p| p.attempts).collect::<Vec<_>>()
    );
}

#[test]
fn an_unreachable_controller_stops_the_mission_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    // Every packet the controller sends is lost: the robot never hears it.
    c.rig.faults.link = Some(FaultConfig {
        drop: 1.0,
        ..FaultConfig::default()
    });
    let err = mission(&c).unwrap_err();
    assert!(
        matches!(err, MissionError::ControllerUnreachable { .. }),
        "{err}"
    );
    assert!(err.to_string().contains("unreachable"), "{err}");
}

#[test]
fn stopping_mid_mission_stops_the_arm_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.rig.speedup = 2.0;
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let _one = SERIAL
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let setter = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(2500));
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        })
    };
    let t = std::time::Instant::now();
    let err = run_inspection(&c.check().unwrap(), &stop, |_| {}).unwrap_err();
    setter.join().unwrap();
    assert!(matches!(err, MissionError::Interrupted), "{err}");
    assert!(err.to_string().contains("arm was stopped"), "{err}");
    // It stopped promptly, not at the end of the plan.
    assert!(t.elapsed() < Duration::from_secs(6), "{:?}", t.elapsed());
}

#[test]
fn a_front_end_sees_the_frame_the_candidates_the_plan_every_sample_and_every_verdict() {
    use crackbot_mission::inspect::Progress;
    let dir = tempfile::tempdir().unwrap();
    let mut c = config(dir.path());
    c.plan.planner.passes = 1;
    let mut events = Vec::new();
    let r = {
        let _one = SERIAL
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let stop = AtomicBool::new(false);
        run_inspection(&c.check().unwrap(), &stop, |p| events.push(p.clone())).unwrap()
    };
    let frame = events
        .iter()
        .find_map(|e| match e {
            Progress::Frame(f) => Some(f.clone()),
            _ => None,
        })
        .expect("no frame event");
    assert_eq!(r.frame.as_ref(), Some(&frame), "the report keeps the frame");
    let img = image::open(&frame.path).unwrap();
    assert_eq!((img.width(), img.height()), (frame.width, frame.height));
    // The overlay's homography puts each candidate's centre inside the frame.
    let detections = events
        .iter()
        .find_map(|e| match e {
            Progress::Perceived { detections, .. } => Some(detections.clone()),
            _ => None,
        })
        .expect("no detections event");
    assert_eq!(detections, r.candidates);
    for d in &detections {
        let m = frame.surface_to_image;
        let (x, y) = (d.centre_mm[0], d.centre_mm[1]);
        let w = m[2][0] * x + m[2][1] * y + m[2][2];
        let px = (m[0][0] * x + m[0][1] * y + m[0][2]) / w;
        let py = (m[1][0] * x + m[1][1] * y + m[1][2]) / w;
        assert!(
            (0.0..f64::from(frame.width)).contains(&px)
                && (0.0..f64::from(frame.height)).contains(&py),
            "candidate {} maps to ({px}, {py})",
            d.id
        );
    }
    let plan = events
        .iter()
        .find_map(|e| match e {
            Progress::Planned { plan, .. } => Some(plan.clone()),
            _ => None,
        })
        .expect("no plan event");
    assert_eq!(Some(plan), r.plan);
    // Samples arrive in time order, in many chunks, and cover every pass's samples.
    let chunks: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Progress::Samples { samples } => Some(samples.clone()),
            _ => None,
        })
        .collect();
    let all: Vec<_> = chunks.iter().flatten().collect();
    // One stroke at speed-up 8 arrives in about 40 chunks on an idle machine; under a heavy
    // load the host drains larger ones (20 seen in CI beside a training job). Streaming, not
    // one batch at the end, is what is asserted.
    assert!(chunks.len() > 10, "{} chunks", chunks.len());
    assert!(all.windows(2).all(|w| w[1].t_s >= w[0].t_s - 1e-3));
    let slid: usize = r.passes.iter().map(|p| p.samples).sum();
    assert!(all.len() >= slid, "{} live samples, {slid} slid", all.len());
    // One verdict event per pass, equal to the report's.
    let passes: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Progress::Slid { pass, .. } => Some((**pass).clone()),
            _ => None,
        })
        .collect();
    assert_eq!(passes, r.passes);
    // While each pass is under way, its running verdict every 0.1 s: before its own verdict,
    // after the one before, over more and more windows, with the finger along the stroke.
    let mut current = None;
    let mut feelings: Vec<(u32, Vec<crackbot_mission::inspect::Feeling>)> = Vec::new();
    for e in &events {
        match e {
            Progress::Feeling(f) => {
                assert!(
                    current.is_none_or(|c| c < f.slide),
                    "{f:?} after its own verdict"
                );
                match feelings.last_mut() {
                    Some((id, v)) if *id == f.slide => v.push(f.clone()),
                    _ => feelings.push((f.slide, vec![f.clone()])),
                }
            }
            Progress::Slid { pass, .. } => current = Some(pass.id),
            _ => {}
        }
    }
    let ids: Vec<u32> = feelings.iter().map(|(id, _)| *id).collect();
    let pass_ids: Vec<u32> = r.passes.iter().map(|p| p.id).collect();
    assert_eq!(ids, pass_ids, "one run of running verdicts per pass");
    for ((_, fs), pass) in feelings.iter().zip(&r.passes) {
        assert!(
            fs.len() >= 3,
            "{} running verdicts for pass {}",
            fs.len(),
            pass.id
        );
        assert!(fs.windows(2).all(|w| w[1].windows > w[0].windows));
        let stroke = (pass.end_mm[0] - pass.start_mm[0]).hypot(pass.end_mm[1] - pass.start_mm[1]);
        for f in fs {
            assert!((0.0..=1.0).contains(&f.confidence), "{f:?}");
            assert!(
                (-1.0..=stroke + 1.0).contains(&f.along_mm),
                "{f:?}, stroke {stroke}"
            );
            assert!(
                ["no crack", "crack", "bump", "wavy"].contains(&f.class.as_str()),
                "{f:?}"
            );
        }
        assert!(fs.last().unwrap().along_mm > 0.5 * stroke, "{fs:?}");
    }
    // The stream's health, twice a second: a rate near 400 Hz × the speed-up, counters growing.
    let health: Vec<_> = events
        .iter()
        .filter_map(|e| match e {
            Progress::Health(h) => Some(*h),
            _ => None,
        })
        .collect();
    assert!(health.len() >= 2, "{} health events", health.len());
    let rate = health[health.len() - 1].sample_rate_hz;
    assert!(
        (0.5 * 400.0 * c.rig.speedup..1.5 * 400.0 * c.rig.speedup).contains(&rate),
        "{rate} Hz"
    );
    assert!(health.windows(2).all(|w| w[1].frames >= w[0].frames));
    assert!(
        // (A packet that crosses the link's start-up may be refused; none after.)
        health
            .iter()
            .all(|h| h.crc_errors == 0 && h.link_rejected <= 1),
        "{health:?}"
    );
    assert!(health
        .iter()
        .all(|h| h.state_age_ms.is_some_and(|a| a < 500.0)));
}

#[test]
fn printed_decoys_are_rejected_by_the_raised_pass_and_cracks_kept() {
    use crackbot_research::finger_budget;
    use crackbot_tactile::print_check::PRINT_RATIO;
    // A trial scene (seed 1000, one of those the check's threshold was chosen on): two cracks of
    // the authors' printed profile and two printed decoys, all proposed by the detector.
    let scene = trial_scene(1000);
    let decoys = scene
        .features
        .iter()
        .filter(|f| matches!(f, crackbot_sim::Feature::Decoy { .. }))
        .count();
    assert_eq!(decoys, 2);
    let dir = tempfile::tempdir().unwrap();
    let r = fast_mission_in(&scene, dir.path());
    let budget = finger_budget(&scene, &r);
    assert_eq!(budget.decoy[0], 0, "a decoy was confirmed: {budget:?}");
    assert!(budget.decoy[1] >= 1, "{budget:?}");
    assert!(budget.crack[0] >= 1, "no crack confirmed: {budget:?}");
    // Every candidate the contact slide read as a crack was passed over raised, and its ratio
    // decided: cracks below the threshold, prints above it.
    for c in &r.cracks {
        let ratio = c
            .evidence
            .height_ratio
            .expect("a confirmed crack was checked");
        assert!(ratio < PRINT_RATIO, "{ratio}");
        let id = c.candidate.expect("a candidate");
        assert!(dir.path().join(format!("raised-{id:03}.csv")).is_file());
    }
    let prints: Vec<_> = r
        .rejected
        .iter()
        .filter(|x| x.felt.starts_with("a print"))
        .collect();
    assert!(!prints.is_empty(), "{:?}", r.rejected);
    for p in prints {
        assert!(p.height_ratio.is_some_and(|h| h > PRINT_RATIO), "{p:?}");
    }
    // Every rejected candidate carries the recognition votes it was judged by: a print reads
    // as a crack to the finger, which is why it needed the raised pass.
    for x in &r.rejected {
        assert_eq!(x.votes.len(), r.cracks[0].evidence.votes.len(), "{x:?}");
        assert!(x.votes.iter().all(|v| v.is_finite() && *v >= 0.0), "{x:?}");
        if x.felt.starts_with("a print") {
            let top = x.votes.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            assert!(top > 0.0, "{x:?}");
        }
    }
}

#[test]
fn a_raised_pass_stops_over_a_screw_head_and_the_candidate_on_it_is_rejected() {
    use crackbot_sim::Feature;
    // Trial scene 9073: the from-scratch detector proposes the rim of a 2.2 mm screw head next
    // to a bump, the finger reads it as a crack, and the raised pass (2 mm up) runs into the head.
    let scene = trial_scene(9073);
    let screws: Vec<([f64; 2], f64)> = scene
        .features
        .iter()
        .filter_map(|f| match f {
            Feature::Screw {
                centre,
                head_diameter_mm,
                ..
            } => Some((*centre, head_diameter_mm / 2.0)),
            _ => None,
        })
        .collect();
    assert!(!screws.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let r = fast_mission_scratch_eye(&scene, dir.path());
    let stood: Vec<_> = r
        .rejected
        .iter()
        .filter(|x| x.felt.starts_with("something standing"))
        .collect();
    // At least the candidate on the 2.2 mm head; since the thinning keeps thin diagonal cracks
    // (2026-11-27), also a printed line's end that lies on the other screw's head.
    assert!(!stood.is_empty(), "{:?}", r.rejected);
    // Each was a screw's: its centre lies within a head's radius (plus the finger's reach) of
    // one, and no reported crack does.
    let near_screw = |p: [f64; 2]| {
        screws
            .iter()
            .any(|(s, rad)| (p[0] - s[0]).hypot(p[1] - s[1]) < rad + 4.0)
    };
    assert!(!r.cracks.is_empty());
    for k in &r.cracks {
        assert!(!near_screw(k.position_mm), "{k:?}");
        assert!(k.evidence.doubts.iter().all(|d| !matches!(
            d,
            crackbot_mission::inspect::CrackDoubt::RaisedPassStopped { .. }
        )));
    }
    for x in &stood {
        assert!(near_screw(x.position_mm), "{x:?}");
        // The pass was stopped near its start (it would have run at least 9 mm: a 6 mm stroke
        // and 1.5 mm past either end).
        let raised =
            std::fs::read_to_string(dir.path().join(format!("raised-{:03}.csv", x.candidate)))
                .unwrap();
        let reached = raised
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(5).unwrap().parse::<f64>().unwrap())
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(reached < 6.0, "{x:?}: {reached}");
    }
}

#[test]
fn a_stroke_that_ends_off_the_sound_surface_is_made_again_beside_it() {
    use crackbot_research::score;
    // Trial scene 9246: the from-scratch detector takes a 3.7 mm high screw head for a crack. The stroke
    // across that candidate starts on the head (its ends read about 730 and 310 counts, where
    // the sound surface reads about 310 and the dark level is 285), so it cannot tell a crack
    // from the head. The ends' margin is wide (0.05 of the brighter end's signal, against the
    // 0.6 that is asked), so the restroke does not hang on the simulated noise.
    let scene = trial_scene(9246);
    let screw = scene
        .features
        .iter()
        .find_map(|f| match f {
            crackbot_sim::Feature::Screw { centre, .. } => Some(*centre),
            _ => None,
        })
        .expect("scene 9246 has a screw");
    // Kept until the end: the test reads a recording the report names.
    let dir = tempfile::tempdir().unwrap();
    let r = fast_mission_scratch_eye(&scene, dir.path());
    let not_judged: Vec<_> = r
        .passes
        .iter()
        .filter(|p| {
            matches!(
                p.doubt,
                Some(crackbot_mission::inspect::PassDoubt::NotJudged { .. })
            )
        })
        .collect();
    assert_eq!(not_judged.len(), 1, "{:#?}", r.passes);
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let p = not_judged[0];
    assert_eq!(p.class, None);
    // It is the stroke that began on the screw head.
    assert!(
        dist(p.start_mm, screw).min(dist(p.end_mm, screw)) < 5.0,
        "{p:?}"
    );
    // Its recording is kept, and the candidate was stroked again on a parallel line 5 mm
    // along it, and judged there: nothing to report.
    assert!(std::path::Path::new(&p.recording).is_file());
    let again = r
        .passes
        .iter()
        .find(|q| q.candidate == p.candidate && q.id > p.id)
        .expect("stroked again");
    assert!(again.class.is_some(), "{again:?}");
    assert!(
        (dist(p.start_mm, again.start_mm) - 5.0).abs() < 1e-6,
        "{again:?}"
    );
    assert!(
        (dist(p.end_mm, again.end_mm) - 5.0).abs() < 1e-6,
        "{again:?}"
    );
    // Once only.
    assert_eq!(
        r.passes
            .iter()
            .filter(|q| q.candidate == p.candidate)
            .count(),
        2
    );
    assert!(
        r.cracks.iter().all(|k| k.candidate != p.candidate),
        "{:#?}",
        r.cracks
    );
    // The scene's three cracks are found.
    let s = score(&scene, &r);
    assert_eq!(
        s.correct, s.cracks,
        "{s:?}\n{:#?}\n{:#?}",
        r.cracks, r.passes
    );
}

#[test]
fn a_ratio_in_doubt_is_measured_again_and_both_estimates_decide() {
    use crackbot_mission::inspect::{
        PRINT_CHECK_PASSES_IN_DOUBT, PRINT_RATIO_DOUBT, PRINT_RATIO_SETTLED,
    };
    use crackbot_tactile::print_check::PRINT_RATIO;
    // Trial scene 9430: a 0.51 mm crack whose raised passes read 0.88-0.90 (at real time and
    // at speed-up 2), where a crack's and a print's ratios overlap. A run that reads it outside
    // the band (one in about twenty here, under load) also runs scene 9843, whose 1.16 mm print
    // first reads 0.85-0.88.
    let mut doubted = 0;
    for seed in [9430, 9843] {
        let scene = trial_scene(seed);
        let dir = tempfile::tempdir().unwrap();
        let r = fast_mission_in(&scene, dir.path());
        // Every candidate passed over raised.
        struct Checked {
            id: u64,
            mean: Option<f64>,
            ratios: Vec<f64>,
            floors: Vec<Option<f64>>,
            reported: bool,
            felt: String,
        }
        let mut checked: Vec<Checked> = r
            .cracks
            .iter()
            .filter_map(|k| {
                Some(Checked {
                    id: k.candidate?,
                    mean: k.evidence.height_ratio,
                    ratios: k.evidence.print_ratios.clone(),
                    floors: k.evidence.floor_ratios.clone(),
                    reported: true,
                    felt: String::new(),
                })
            })
            .collect();
        checked.extend(r.rejected.iter().map(|k| Checked {
            id: k.candidate,
            mean: k.height_ratio,
            ratios: k.print_ratios.clone(),
            floors: k.floor_ratios.clone(),
            reported: false,
            felt: k.felt.clone(),
        }));
        for Checked {
            id,
            mean,
            ratios,
            floors,
            reported,
            felt,
        } in checked
        {
            let Some(&first) = ratios.first() else {
                assert_eq!(mean, None);
                continue;
            };
            let mean = mean.expect("a mean where passes gave ratios");
            let extra = dir.path().join(format!("raised-{id:03}-2.csv"));
            if (first - PRINT_RATIO).abs() < PRINT_RATIO_DOUBT {
                doubted += 1;
                // One pass each way at least, and two more unless the first two settled.
                let pair = |n: usize| {
                    let m: f64 = ratios[..n]
                        .iter()
                        .zip(&floors)
                        .map(|(&p, f)| f.map_or(p, |f| 0.5 * (p + f)))
                        .sum::<f64>()
                        / n as f64;
                    (m - PRINT_RATIO).abs() >= PRINT_RATIO_SETTLED
                };
                match ratios.len() {
                    2 => assert!(pair(2), "{id}: {ratios:?} {floors:?}"),
                    PRINT_CHECK_PASSES_IN_DOUBT => assert!(!pair(2), "{id}: {ratios:?} {floors:?}"),
                    n => panic!("{id}: {n} raised passes: {ratios:?}"),
                }
                // In doubt, each pass's print and floor ratios are averaged, and the passes' mean
                // decides.
                assert_eq!(floors.len(), ratios.len(), "{id}: {floors:?}");
                let average = ratios
                    .iter()
                    .zip(&floors)
                    .map(|(&p, f)| f.map_or(p, |f| 0.5 * (p + f)))
                    .sum::<f64>()
                    / ratios.len() as f64;
                assert!(
                    (mean - average).abs() < 1e-12,
                    "{id}: {mean} {ratios:?} {floors:?}"
                );
                // Each pass is kept, and they go back and forth.
                let direction = |k: usize| {
                    let path = dir.path().join(format!("raised-{id:03}-{k}.csv"));
                    let text = std::fs::read_to_string(&path).expect("raised pass kept");
                    text.lines()
                        .nth(1)
                        .unwrap()
                        .split(',')
                        .nth(4)
                        .unwrap()
                        .to_string()
                };
                for k in 2..ratios.len() {
                    assert_ne!(direction(k), direction(k + 1), "{id}");
                }
                // Over one line, the passes read alike: where there are three or more, their
                // median absolute deviation is under a quarter of the gap between a crack's
                // ratio (about 0.78) and a print's (1); most lie within a few hundredths, and one
                // pass may stray (0.64 among three at 0.87-0.90 once here, under load). Of two
                // passes that settled, one stray cannot be told from the other (0.82 and 0.94
                // once, in CI), so two are not held to it.
                let median = |v: &mut Vec<f64>| {
                    v.sort_by(f64::total_cmp);
                    let n = v.len();
                    0.5 * (v[(n - 1) / 2] + v[n / 2])
                };
                let centre = median(&mut ratios.clone());
                let spread = median(&mut ratios.iter().map(|x| (x - centre).abs()).collect());
                assert!(ratios.len() < 3 || spread < 0.055, "{id}: {ratios:?}");
                // The mean decides: a print above the threshold, not below it.
                assert_eq!(
                    felt.starts_with("a print"),
                    mean > PRINT_RATIO,
                    "{id}: {felt}"
                );
                assert!(!reported || mean <= PRINT_RATIO, "{id}: {ratios:?}");
            } else {
                assert_eq!(ratios.len(), 1, "{id}: {ratios:?}");
                assert!(floors.is_empty(), "{id}: {floors:?}");
                assert!((mean - first).abs() < 1e-12, "{id}: {mean} {ratios:?}");
                assert!(!extra.exists(), "{id}");
            }
        }
        if doubted > 0 {
            break;
        }
    }
    assert!(
        doubted >= 1,
        "no candidate in doubt in scenes 9430 and 9843"
    );
}

#[test]
fn a_narrow_print_in_doubt_is_judged_by_its_floor_ratio_too() {
    use crackbot_mission::inspect::PRINT_CHECK_PASSES_IN_DOUBT;
    use crackbot_research::score;
    use crackbot_tactile::print_check::PRINT_RATIO;
    // Trial scene 9843: a printed decoy 1.16 mm wide whose four raised passes' print ratios
    // averaged 0.875 at real time, and it was reported as a crack. Its floor ratios read about
    // 1.04: ink keeps its share raised. In doubt, the mean of the two estimates decides.
    let scene = trial_scene(9843);
    // Its first print ratio reads 0.85-0.88 in nearly every run; a run that reads it outside
    // the doubt band (under heavy load here, about one in twenty) tests nothing of this, and
    // the mission is run once more. A run with the print in doubt is judged. The scene was
    // chosen with the from-scratch eye, which it keeps: the fine-tuned default's stroke over the
    // crack at (120, 67) mm reads no dip raised and rejects it as something else (2026-12-08).
    for attempt in 0..2 {
        let dir = tempfile::tempdir().unwrap();
        let r = fast_mission_scratch_eye(&scene, dir.path());
        let in_doubt = r.cracks.iter().any(|k| !k.evidence.floor_ratios.is_empty())
            || r.rejected.iter().any(|k| !k.floor_ratios.is_empty());
        if !in_doubt && attempt == 0 {
            continue;
        }
        let s = score(&scene, &r);
        assert_eq!(s.false_reports, 0, "{s:?}\n{:#?}", r.cracks);
        assert_eq!(s.correct, s.cracks, "{s:?}\n{:#?}", r.rejected);
        // The print was measured in doubt and told by both estimates: its floor ratios are
        // above the threshold, and so is the mean that decided.
        let print = r
            .rejected
            .iter()
            .find(|k| !k.floor_ratios.is_empty())
            .unwrap_or_else(|| panic!("no candidate judged in doubt: {:#?}", r.rejected));
        assert!(print.felt.starts_with("a print"), "{}", print.felt);
        let n = print.print_ratios.len();
        assert!(n == 2 || n == PRINT_CHECK_PASSES_IN_DOUBT, "{print:?}");
        assert_eq!(print.floor_ratios.len(), n);
        let floors: Vec<f64> = print.floor_ratios.iter().flatten().copied().collect();
        assert_eq!(floors.len(), n, "{print:?}");
        assert!(
            floors.iter().sum::<f64>() / floors.len() as f64 > PRINT_RATIO,
            "{print:?}"
        );
        assert!(
            print.height_ratio.is_some_and(|h| h > PRINT_RATIO),
            "{print:?}"
        );
        return;
    }
}

#[test]
fn a_crack_whose_raised_passes_reach_a_print_past_its_stroke_is_still_a_crack() {
    use crackbot_sim::surface::distance_to_polyline;
    // Trial scene 11998: a 0.77 mm crack whose stroke ends 1.7 mm short of a 3.5 mm print.
    // The raised passes over it overrun the stroke and their fibre looks ahead: those towards
    // the print reached it, its dip was their deepest point, and their floor ratios read
    // 1.15-1.17 against the profile fit's 0.81-0.86. In doubt, the mean of the two (0.91)
    // rejected the crack as a print (real time, 2026-11-29). The raised dip is now the one
    // that lines up with the contact dip.
    let (scene, path) = trial_scene_and_thin_line(11998, true);
    let on_it = |p: [f64; 2]| distance_to_polyline(&path, p) < 3.0;
    let r = fast_mission(&scene);
    for k in r.rejected.iter().filter(|k| on_it(k.position_mm)) {
        assert!(!k.felt.starts_with("a print"), "{k:?}");
    }
    let evidence = &reported_as_a_crack(&r, on_it).evidence;
    assert!(
        evidence.floor_ratios.iter().flatten().all(|&f| f < 1.0),
        "{evidence:?}"
    );
}

#[test]
fn a_crack_on_a_bumps_flank_is_passed_over_again_as_high_above_it_as_the_check_needs() {
    use crackbot_sim::surface::distance_to_polyline;
    // Trial scene 11668: a 1.39 mm crack crosses the flank of a 1.4 mm bump, 0.85 mm up where
    // its stroke crosses it. The raised pass, held 2 mm above the plate, was 1.2 mm above the
    // surface there, the crack kept 94 % of its dip as a print does, and it was rejected as a
    // print (real time, 2026-11-28). The pass is now made again as far above the surface as
    // the check's height.
    let (scene, path) = trial_scene_and_crack(11668, 0);
    let on_it = |p: [f64; 2]| distance_to_polyline(&path, p) < 3.0;
    let dir = tempfile::tempdir().unwrap();
    let r = fast_mission_in(&scene, dir.path());
    let crack = reported_as_a_crack(&r, on_it);
    let again = crack
        .evidence
        .doubts
        .iter()
        .find_map(|d| match d {
            crackbot_mission::inspect::CrackDoubt::SurfaceRise { rise_mm, height_mm } => {
                Some((*rise_mm, *height_mm))
            }
            _ => None,
        })
        .unwrap_or_else(|| panic!("no pass made again: {:?}", crack.evidence));
    assert!(again.0 > 0.0 && again.1 > 2.0, "{again:?}");
    let id = crack.candidate.expect("a candidate");
    assert!(dir
        .path()
        .join(format!("raised-{id:03}-again.csv"))
        .is_file());
}

#[test]
fn a_crack_on_a_bumps_flank_that_reads_a_crack_is_not_passed_over_again() {
    use crackbot_sim::surface::distance_to_polyline;
    // Trial scene 12747: a 0.93 mm crack on the flank of a 1 mm bump. Its first raised pass
    // read 0.85 (a crack, in doubt); made again 0.46 mm higher, the pass over the flank's
    // sloping level misread its dip (0.05, "neither"), and the crack was rejected (real time,
    // 2026-11-29). Nearer the surface a crack keeps more of its dip, so one that reads a crack
    // is left to the passes at the check's height.
    let (scene, path) = trial_scene_and_crack(12747, 1);
    let on_it = |p: [f64; 2]| distance_to_polyline(&path, p) < 3.0;
    let r = fast_mission(&scene);
    let crack = reported_as_a_crack(&r, on_it);
    assert!(
        crack
            .evidence
            .doubts
            .iter()
            .all(|d| !matches!(d, crackbot_mission::inspect::CrackDoubt::SurfaceRise { .. })),
        "{:?}",
        crack.evidence
    );
}

#[test]
fn a_print_whose_stroke_ends_on_a_darker_line_is_judged_by_its_own_dip() {
    use crackbot_sim::surface::distance_to_polyline;
    // Trial scene 11494: the stroke across a 0.72 mm printed line ends on a 3.7 mm print. Its
    // proximity dips over both, back to the surface between them, and the candidate was
    // located on its own dip; but the print check compared the raised passes with the whole
    // stroke, whose deepest point is the wide print: the thin print's raised dip, against
    // that, read 0.59 and it was confirmed as a crack (real time, 2026-11-29). Its own dip
    // keeps its share raised.
    let (scene, path) = trial_scene_and_thin_line(11494, false);
    let on_it = |p: [f64; 2]| distance_to_polyline(&path, p) < 2.5;
    let r = fast_mission(&scene);
    assert!(
        r.cracks.iter().all(|k| !on_it(k.position_mm)),
        "{:#?}",
        r.cracks
    );
    let print = r
        .rejected
        .iter()
        .find(|k| on_it(k.position_mm))
        .unwrap_or_else(|| panic!("nothing on the print was judged: {:#?}", r.rejected));
    assert!(print.felt.starts_with("a print"), "{print:?}");
}

#[test]
fn a_stroke_across_two_cracks_reports_its_candidate_where_its_own_dip_is() {
    use crackbot_research::score;
    // Trial scene 9570: the stroke across a 0.76 mm crack's candidate also runs into a 3.6 mm
    // crack 4.9 mm away. Its proximity channel dips over both, back to the surface between
    // them, and the localiser's one dip spanning both (8.5 mm wide) put the report between the
    // cracks: a false report and a missed crack.
    let scene = trial_scene(9570);
    let r = fast_mission(&scene);
    let s = score(&scene, &r);
    assert_eq!(s.false_reports, 0, "{s:?}\n{:#?}", r.passes);
    assert!(s.correct >= 2, "{s:?}");
    assert!(
        s.localisation_mm.iter().all(|&e| e < 1.0),
        "{s:?}\n{:#?}",
        r.passes
    );
    // Every judged stroke's dip is about as wide as its crack (none over 5 mm: the widest
    // crack is 3.6 mm).
    for p in r.passes.iter().filter(|p| p.class.is_some()) {
        assert!(p.dip.as_ref().is_none_or(|d| d.width_mm < 5.0), "{p:?}");
    }
}

#[test]
fn bad_confirmation_settings_are_refused_before_anything_starts() {
    use crackbot_mission::MissionError;
    let dir = tempfile::tempdir().unwrap();
    // The setting a mission with `change` refuses, by name.
    let refused = |change: &dyn Fn(&mut InspectConfig)| {
        let mut c = config(dir.path());
        change(&mut c);
        match mission(&c).unwrap_err() {
            MissionError::Setting { field, value, .. } => {
                let e = MissionError::Setting {
                    field,
                    value,
                    allowed: "",
                };
                assert!(e.to_string().contains(field), "{e}");
                field
            }
            other => panic!("{other}"),
        }
    };
    assert_eq!(
        refused(&|c| c.touch.min_dip_counts = f64::NAN),
        "touch.min_dip_counts"
    );
    assert_eq!(
        refused(&|c| c.print_check.height_mm = Some(0.1)),
        "print_check.height_mm"
    );
    for bad in [0.0, 1.5, f64::NAN] {
        assert_eq!(
            refused(&|c| c.judge.doubted_dip_confidence = Some(bad)),
            "judge.doubted_dip_confidence"
        );
    }
    assert_eq!(refused(&|c| c.pieces.gap_mm = Some(-1.0)), "pieces.gap_mm");
    for bad in [-0.5, f64::INFINITY] {
        assert_eq!(
            refused(&|c| c.pieces.trace_gap_mm = Some(bad)),
            "pieces.trace_gap_mm"
        );
    }
}
