//! The planner's estimates checked against the simulator: the targeted plan for the simulator's
//! default scene (four cracks and the printed decoy, given to the planner as centre-line
//! polylines in mm, as a detector plus homography would), every planned slide run by the
//! simulated finger (`crackbot_sim::run::SlideSim`, calibrated sensor) on that scene's surface.
//!
//! * time: the simulated arm finishes each slide (forth and back) when the planner's
//!   `slide_time_s` says, to within one 400 Hz sample;
//! * geometry: every slide starts and ends with the whole tip on sound (flat) surface, and
//!   crosses its crack (the surface under the slide dips; the simulated tip drops into every
//!   crack, not into the printed decoy);
//! * the whole plan, travel included, run pass by pass on the simulated controller
//!   (`crackbot_controller::World`) takes the planner's travel + slide estimate to within the
//!   controller's tick rounding, with and without the print check's raised pass after every
//!   slide; settling is modelled by neither and is the estimate only.
//!
//! `--nocapture` prints the per-slide comparison.

use crackbot_planner::{Candidate, Limits, Planner, Settings, Workspace};
use crackbot_sim::plates::calibrated_sensor;
use crackbot_sim::run::{SlideLine, SlideSim, SAMPLE_RATE_HZ};
use crackbot_sim::{Feature, Integrator, Scene};

#[test]
fn planned_slides_take_the_estimated_time_in_the_simulator_and_cross_their_cracks() {
    let scene = Scene::builtin_default();
    let surface = scene.surface();
    let sensor = calibrated_sensor();
    let tip = sensor.finger.tip_radius_mm;
    let m = &scene.manipulator;
    let ws = Workspace::new(
        m.workspace_min_mm[0],
        m.workspace_max_mm[0],
        m.workspace_min_mm[1],
        m.workspace_max_mm[1],
    )
    .expect("workspace");
    let settings = Settings {
        slide_speed_mm_s: m.slide_speed_mm_s,
        travel_speed_mm_s: m.travel_speed_mm_s,
        reach_mm: tip,
        ..Settings::default()
    };
    let planner = Planner::new(ws, Limits::default(), settings.clone()).expect("planner");

    // The scene's cracks and decoy, as candidates: (id, polyline, width, is a crack).
    let mut truth = Vec::new();
    for (i, f) in scene.features.iter().enumerate() {
        match f {
            Feature::Crack { path, width_mm, .. } => {
                truth.push((i as u64, path.clone(), *width_mm, true));
            }
            Feature::Decoy { path, width_mm, .. } => {
                truth.push((i as u64, path.clone(), *width_mm, false));
            }
            _ => {}
        }
    }
    assert_eq!(truth.iter().filter(|t| t.3).count(), 4);
    let candidates: Vec<Candidate> = truth
        .iter()
        .map(|(id, path, w, _)| Candidate::from_polyline(*id, path, *w, 0.9).expect("candidate"))
        .collect();
    let plan = planner.targeted(&candidates).expect("plan");
    assert!(plan.unreachable.is_empty(), "{:?}", plan.unreachable);
    assert_eq!(plan.slides.len(), candidates.len());

    println!("| candidate | stroke mm | estimate s | simulated s | surface min mm | tip min mm | tip travel mm |");
    println!("|---|---|---|---|---|---|---|");
    let mut simulated_total = 0.0;
    for slide in &plan.slides {
        let id = slide.candidates[0];
        let is_crack = truth.iter().find(|t| t.0 == id).expect("truth").3;
        let d = [
            slide.end_mm[0] - slide.start_mm[0],
            slide.end_mm[1] - slide.start_mm[1],
        ];
        let len = d[0].hypot(d[1]);
        let u = [d[0] / len, d[1] / len];
        let at = |s: f64| [slide.start_mm[0] + s * u[0], slide.start_mm[1] + s * u[1]];

        // Sound surface under the whole tip plus the minimum margin at both ends; the crack
        // somewhere between.
        let sound = tip + settings.min_margin_mm;
        let steps = (len / 0.05).ceil() as usize;
        let heights: Vec<(f64, f64)> = (0..=steps)
            .map(|k| {
                let s = len * k as f64 / steps as f64;
                (s, surface.height_mm(at(s)))
            })
            .collect();
        for &(s, h) in &heights {
            if s <= sound || s >= len - sound {
                assert_eq!(h, 0.0, "candidate {id}: not sound at {s:.2} mm of {len:.2}");
            }
        }
        let surface_min = heights.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
        if is_crack {
            assert!(
                surface_min < -0.1,
                "candidate {id}: the slide misses its crack ({surface_min} mm)"
            );
        } else {
            assert_eq!(surface_min, 0.0, "the decoy is flat");
        }

        // The simulated finger runs the slide.
        let line = SlideLine {
            start: slide.start_mm,
            direction: u,
            stroke_mm: slide.stroke_mm,
            speed_mm_s: slide.speed_mm_s,
        };
        let mut sim =
            SlideSim::new(&surface, 1.0, &line, &sensor, Integrator::default(), id).expect("sim");
        let n = (slide.duration_s * SAMPLE_RATE_HZ).ceil() as usize + 40;
        // The arm's strokes repeat: the slide ends where, after the far end, the arm is back
        // nearest to its start.
        let mut reached_end = false;
        let mut back: Option<(f64, f64)> = None; // (|arm|, t)
        let (mut tip_min, mut tip_lo, mut tip_hi) =
            (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for _ in 0..n {
            let s = sim.next_sample().expect("sample");
            assert!(
                s.arm_mm >= -1e-9 && s.arm_mm <= slide.stroke_mm + 1e-9,
                "arm off the slide: {}",
                s.arm_mm
            );
            reached_end |= (s.arm_mm - slide.stroke_mm).abs() < 1e-3;
            if reached_end && back.is_none_or(|(a, _)| s.arm_mm.abs() < a) {
                back = Some((s.arm_mm.abs(), s.t));
            }
            if s.t <= slide.duration_s {
                tip_min = tip_min.min(s.tip_z_mm);
                tip_lo = tip_lo.min(s.tip_x_mm);
                tip_hi = tip_hi.max(s.tip_x_mm);
            }
        }
        let (left, simulated) = back.expect("the arm came back");
        assert!(left < 1e-3, "the arm did not come back: {left} mm");
        simulated_total += simulated;
        println!(
            "| {id}{} | {:.2} | {:.3} | {:.3} | {:.2} | {:.3} | {:.2} |",
            if is_crack { "" } else { " (decoy)" },
            slide.stroke_mm,
            slide.duration_s,
            simulated,
            surface_min,
            tip_min,
            tip_hi - tip_lo
        );
        assert!(
            (simulated - slide.duration_s).abs() <= 1.0 / SAMPLE_RATE_HZ + 1e-9,
            "{simulated} vs {}",
            slide.duration_s
        );
        assert!((sim.slide_time() - slide.duration_s).abs() < 1e-9);
        if is_crack {
            assert!(
                tip_min < -0.01,
                "candidate {id}: the simulated tip never drops into the crack ({tip_min} mm)"
            );
        } else {
            assert!(
                tip_min > -0.05,
                "the decoy is flat to the touch ({tip_min} mm)"
            );
        }
        // The tip follows the arm across the slide (it may lag where it catches an edge).
        assert!(
            tip_hi - tip_lo > 0.8 * slide.stroke_mm,
            "candidate {id}: tip travel {}",
            tip_hi - tip_lo
        );
    }
    println!(
        "slides: estimate {:.2} s, simulated {:.2} s; travel {:.1} mm = {:.2} s and settling {:.1} s estimated only; plan {:.2} s",
        plan.time.slide_s, simulated_total, plan.travel_mm, plan.time.travel_s, plan.time.settle_s, plan.estimated_s
    );
    assert!(
        (simulated_total - plan.time.slide_s).abs()
            <= plan.slides.len() as f64 / SAMPLE_RATE_HZ + 1e-9
    );
}

/// The whole targeted plan of the default scene run on the simulated controller
/// (`crackbot_controller::World`: travel at the scene's travel speed, then one stroke per slide
/// command, the finger simulated all along), pass by pass as a mission sends it: the simulated
/// time is the planner's travel + slide estimate to within the controller's rounding (each move
/// and each stroke is a whole number of 400 Hz ticks; a zero-length move takes one tick).
/// Settling is not simulated, so the plan is made with `settle_s = 0`.
#[test]
fn a_whole_plan_takes_the_estimated_time_on_the_simulated_controller() {
    whole_plan_on_the_controller(None);
}

/// The same with the print check's raised pass after every slide
/// (`crackbot_mission::PRINT_CHECK_OVERRUN_MM`, `PRINT_CHECK_SPEED_MM_S`, flown 2 mm up as the
/// mission flies it): the estimate counts each one, and the next move starts where it ends.
#[test]
fn a_whole_plan_with_raised_passes_takes_the_estimated_time_on_the_simulated_controller() {
    whole_plan_on_the_controller(Some(crackbot_planner::RaisedPass {
        overrun_mm: crackbot_mission::PRINT_CHECK_OVERRUN_MM,
        speed_mm_s: crackbot_mission::PRINT_CHECK_SPEED_MM_S,
    }));
}

fn whole_plan_on_the_controller(raised_pass: Option<crackbot_planner::RaisedPass>) {
    use crackbot_controller::World;

    let scene = Scene::builtin_default();
    let mut world = World::new(&scene, 5).expect("world");
    let l = *world.limits();
    let ws = Workspace::new(l.min_mm[0], l.max_mm[0], l.min_mm[1], l.max_mm[1]).expect("workspace");
    let limits = Limits {
        max_slide_speed_mm_s: l.max_slide_speed_mm_s,
        max_travel_speed_mm_s: l.max_travel_speed_mm_s,
    };
    let settings = Settings {
        slide_speed_mm_s: scene.manipulator.slide_speed_mm_s,
        travel_speed_mm_s: scene.manipulator.travel_speed_mm_s,
        reach_mm: scene.sensor.finger.tip_radius_mm,
        settle_s: 0.0,
        raised_pass,
        ..Settings::default()
    };
    let planner = Planner::new(ws, limits, settings).expect("planner");
    assert_eq!(world.pose()[..2], planner.start_mm()[..]);
    let candidates: Vec<Candidate> = scene
        .features
        .iter()
        .enumerate()
        .filter_map(|(i, f)| match f {
            Feature::Crack { path, width_mm, .. } | Feature::Decoy { path, width_mm, .. } => {
                Some(Candidate::from_polyline(i as u64, path, *width_mm, 0.9).expect("candidate"))
            }
            _ => None,
        })
        .collect();
    let plan = planner.targeted(&candidates).expect("plan");
    let mut ticks = 0u64;
    let mut strokes = 0u64;
    let mut id = 0u32;
    for slide in &plan.slides {
        for pass in 0..slide.passes {
            let (a, b) = if pass % 2 == 0 {
                (slide.start_mm, slide.end_mm)
            } else {
                (slide.end_mm, slide.start_mm)
            };
            id += 1;
            world
                .slide(id, a, b, slide.speed_mm_s)
                .expect("the controller accepts the planned slide");
            strokes += 1;
            loop {
                let t = world.step().expect("step");
                ticks += 1;
                if t.finished == Some(id) {
                    break;
                }
                assert!(
                    ticks < 1_000_000,
                    "the controller never finished slide {id}"
                );
            }
        }
        if let Some([from, to]) = crackbot_planner::raised_pass(slide, planner.settings(), &ws) {
            let speed = raised_pass.map_or(0.0, |r| r.speed_mm_s);
            for p in [from, to] {
                world
                    .move_to(p, crackbot_mission::PRINT_CHECK_HEIGHT_MM, speed)
                    .expect("the controller accepts the raised pass");
                strokes += 1;
                loop {
                    let t = world.step().expect("step");
                    ticks += 1;
                    if t.mode == crackbot_controller::Mode::Idle {
                        break;
                    }
                    assert!(ticks < 1_000_000, "the controller never reached {p:?}");
                }
            }
        }
    }
    assert_eq!(
        plan.raised.len(),
        if raised_pass.is_some() {
            2 * plan.slides.len()
        } else {
            0
        }
    );
    let simulated = ticks as f64 / SAMPLE_RATE_HZ;
    let estimate = plan.time.travel_s + plan.time.slide_s + plan.time.raised_s;
    println!(
        "controller: {} strokes and raised moves, simulated {simulated:.3} s, estimate {estimate:.3} s (travel {:.3} + slides {:.3} + raised passes {:.3})",
        strokes, plan.time.travel_s, plan.time.slide_s, plan.time.raised_s
    );
    // Each move and each stroke rounds up to whole ticks (+1 tick each at most).
    assert!(simulated >= estimate - 1e-9, "{simulated} < {estimate}");
    assert!(
        simulated <= estimate + 2.0 * strokes as f64 / SAMPLE_RATE_HZ,
        "{simulated} vs {estimate}"
    );
}
