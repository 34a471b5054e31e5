//! The research crate's unit tests: scoring, the finger's budget, clearances and the tables.

use super::*;
use crate::geometry::stroke_meets;
use crate::trials::retry_once;
use crackbot_mission::inspect::{InspectMode, InspectReport};
use crackbot_mission::MissionError;
use crackbot_sim::{Feature, Scene};

use crackbot_mission::inspect::{Evidence, PassRecord, ReportedCrack};

/// A table of no trials with these means and finger budget.
fn empty_report(vision_correct: f64, fused_correct: f64, finger: FingerBudget) -> TrialsReport {
    TrialsReport {
        trials: Vec::new(),
        vision_correct,
        fused_correct,
        fused_localisation_mm: None,
        fused_width_mae_mm: None,
        fused_extent_width_mae_mm: None,
        paper: [46.66, 92.85],
        finger,
        finger_right_calls: finger.right_call_share(),
        vision_totals: Totals::default(),
        fused_totals: Totals::default(),
        fused_exploration_s: None,
        fused_within_goal: 0,
        fused_by_clearance: ClearanceSplit::default(),
        retried: Vec::new(),
    }
}

#[test]
fn a_mission_that_failed_in_its_link_runs_once_more_and_a_bad_setting_does_not() {
    let stalled = || MissionError::SensorStalled {
        port: "/dev/pts/9".into(),
        detail: "610 samples of the stroke, 832 expected".into(),
    };
    let mut retried = Vec::new();
    let mut calls = Vec::new();
    let ok = retry_once(7, InspectMode::Fused, &mut retried, |again| {
        calls.push(again);
        if again {
            Ok(3)
        } else {
            Err(stalled())
        }
    });
    assert_eq!(ok.unwrap(), 3);
    assert_eq!(calls, vec![false, true]);
    assert_eq!(retried.len(), 1);
    assert_eq!((retried[0].seed, retried[0].mode), (7, InspectMode::Fused));
    assert!(
        retried[0].error.contains("stalled mid-slide"),
        "{retried:?}"
    );
    // Failing twice ends with the second error; a bad setting is not tried again.
    let twice = retry_once(8, InspectMode::Vision, &mut retried, |_| -> Result<(), _> {
        Err(stalled())
    });
    assert!(matches!(twice, Err(MissionError::SensorStalled { .. })));
    assert_eq!(retried.len(), 2);
    let mut n = 0;
    let bad = retry_once(9, InspectMode::Fused, &mut retried, |_| -> Result<(), _> {
        n += 1;
        Err(MissionError::Setting {
            field: "speedup",
            value: 0.0,
            allowed: "> 0",
        })
    });
    assert!(matches!(bad, Err(MissionError::Setting { .. })));
    assert_eq!((n, retried.len()), (1, 2));
    // The table lists what was run again.
    let mut t = empty_report(0.0, 0.0, FingerBudget::default());
    assert!(!t.markdown().contains("run again"));
    t.retried = retried;
    let md = t.markdown();
    assert!(md.contains("run again from the start (2)"), "{md}");
    assert!(md.contains("- trial 7, fused: the sensor stream"), "{md}");
}

#[test]
fn a_table_without_confirmed_cracks_says_so_instead_of_nan() {
    let mut t = empty_report(0.5, 0.0, FingerBudget::default());
    let md = t.markdown();
    assert!(
        md.contains("– (no crack confirmed)") && !md.contains("NaN"),
        "{md}"
    );
    t.fused_localisation_mm = Some(1.234);
    assert!(t.markdown().contains("| 1.23 mm |"));
    assert!(t.markdown().contains("– (no width reported)"));
    t.fused_width_mae_mm = Some(0.75);
    assert!(t.markdown().contains("(mean absolute) | – | 0.75 mm |"));
    assert!(t.markdown().contains("– (no extent reported)"));
    t.fused_extent_width_mae_mm = Some(0.5);
    assert!(t
        .markdown()
        .contains("the dip's extent taken as the width | – | 0.50 mm |"));
    assert!(t
        .markdown()
        .contains("| exploration, mean ± sd (range) | – | – |"));
    t.fused_exploration_s = Spread::of(&[10.0, 14.0, 24.0]);
    t.fused_within_goal = 2;
    t.fused_totals = Totals {
        correct: 5,
        false_reports: 2,
        missed: 1,
    };
    let md = t.markdown();
    assert!(md.contains("| – | 16.0 ± 7.2 s (10.0–24.0) |"), "{md}");
    assert!(
        md.contains("| trials explored within 15 s | – | 2 of 0 |"),
        "{md}"
    );
    assert!(md.contains("| 0 / 0 / 0 | 5 / 2 / 1 |"), "{md}");
}

#[test]
fn spreads_and_totals_add_up() {
    assert_eq!(Spread::of(&[]), None);
    let one = Spread::of(&[3.0]).unwrap();
    assert_eq!((one.mean, one.sd, one.min, one.max), (3.0, 0.0, 3.0, 3.0));
    let s = Spread::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    assert!((s.sd - 1.2909944487358056).abs() < 1e-12, "{s:?}");
    let score = |c, f, m| Score {
        correct: c,
        false_reports: f,
        missed: m,
        ..Score::default()
    };
    let scores = [score(1, 2, 3), score(4, 0, 1)];
    assert_eq!(
        Totals::of(scores.iter()),
        Totals {
            correct: 5,
            false_reports: 2,
            missed: 4
        }
    );
}

fn report_with(positions: &[[f64; 2]]) -> InspectReport {
    let scene = Scene::builtin_default();
    let mut r = InspectReport {
        mode: InspectMode::Fused,
        scene: scene.name.clone(),
        cracks: Vec::new(),
        rejected: Vec::new(),
        candidates: Vec::new(),
        frame: None,
        passes: Vec::new(),
        plan: None,
        elapsed_s: 0.0,
        exploration_s: 0.0,
        stages: Default::default(),
        sensor_clock: None,
        controller_clock: None,
        link: Default::default(),
        out_dir: String::new(),
    };
    for &p in positions {
        r.cracks.push(ReportedCrack {
            candidate: None,
            position_mm: p,
            extent_mm: None,
            class: "crack".into(),
            width_mm: None,
            width_range_mm: None,
            confidence: 1.0,
            evidence: Evidence {
                detector_score: None,
                ..Evidence::default()
            },
        });
    }
    r
}

#[test]
fn printed_cracks_take_the_fitted_profile_and_nothing_else_changes() {
    let scene = Scene::builtin_default();
    let printed = as_printed(&scene);
    let fitted = crackbot_sim::plates::calibrated_samples();
    assert_eq!(printed.features.len(), scene.features.len());
    let mut cracks = 0;
    for (a, b) in scene.features.iter().zip(&printed.features) {
        match (a, b) {
            (
                Feature::Crack {
                    path: p0,
                    width_mm: w0,
                    ..
                },
                Feature::Crack {
                    path: p1,
                    width_mm: w1,
                    depth_mm,
                    wall_angle_deg,
                    ..
                },
            ) => {
                cracks += 1;
                assert_eq!((p0, w0), (p1, w1));
                assert_eq!(*depth_mm, fitted.crack_depth_mm);
                assert_eq!(*wall_angle_deg, fitted.crack_wall_angle_deg);
            }
            _ => assert_eq!(a, b),
        }
    }
    assert_eq!(cracks, 4);
    printed.validate().unwrap();
}

#[test]
fn the_finger_budget_sorts_candidates_by_what_their_strokes_crossed() {
    let scene = Scene::builtin_default();
    // Candidate 1 across the 1 mm crack and candidate 2 across the decoy, both confirmed;
    // candidate 3 over a screw and candidate 4 over bare plate, both rejected. Candidate 2
    // is touched twice (forth and back).
    let mut r = report_with(&[[37.5, 30.0], [40.0, 84.0]]);
    r.cracks[0].candidate = Some(1);
    r.cracks[1].candidate = Some(2);
    let strokes = [
        (1, [37.5, 22.0], [37.5, 38.0]),
        (2, [40.0, 76.0], [40.0, 92.0]),
        (2, [40.0, 92.0], [40.0, 76.0]),
        (3, [184.0, 92.0], [200.0, 92.0]),
        (4, [100.0, 20.0], [100.0, 35.0]),
    ];
    for (k, (candidate, a, b)) in strokes.into_iter().enumerate() {
        r.passes.push(PassRecord {
            id: k as u32 + 1,
            candidate: Some(candidate),
            start_mm: a,
            end_mm: b,
            samples: 1400,
            class: None,
            confidence: 0.0,
            width_mm: None,
            doubt: None,
            dip: None,
            recording: String::new(),
            attempts: 1,
        });
    }
    let b = finger_budget(&scene, &r);
    assert_eq!(
        b,
        FingerBudget {
            crack: [1, 0],
            decoy: [1, 0],
            relief: [0, 1],
            nothing: [0, 1],
            // The 2, 5 and 10 mm cracks.
            untouched_cracks: 3,
        }
    );
    // Candidate 3 joined to candidate 1 as a piece of its crack counts as confirmed.
    r.cracks[0].evidence.pieces.push(3);
    assert_eq!(finger_budget(&scene, &r).relief, [1, 0]);
    // The 5 mm crack's centre line crosses x = 100 mm at y = 64.9 mm. A stroke that ends
    // 3.4 mm before it (perpendicular 3.3 mm) does not touch it; one that ends 1.9 mm before
    // it (inside its 2.5 mm half width) does.
    let crack5 = &scene.features[2];
    assert!(!stroke_meets([100.0, 50.0], [100.0, 61.5], crack5));
    assert!(stroke_meets([100.0, 50.0], [100.0, 63.0], crack5));
    // The paper's count: the crack confirmed, the screw and the bare plate rejected are
    // right; the decoy confirmed is wrong.
    assert_eq!(b.right_calls(), (3, 4));
    assert_eq!(b.right_call_share(), Some(0.75));
    assert_eq!(FingerBudget::default().right_call_share(), None);
    let mut t = empty_report(0.5, 0.5, b);
    assert!(
        t.markdown()
            .contains("on the candidates it touched (how the paper counts its 92.85 %: 13 of 14) | – | 3 of 4, 75.0 % |"),
        "{}",
        t.markdown()
    );
    t.finger.add(&b);
    assert_eq!(t.finger.crack, [2, 0]);
    assert!(
        t.markdown().contains("| a printed decoy | 2 | 0 |"),
        "{}",
        t.markdown()
    );
    assert!(empty_report(0.5, 0.5, FingerBudget::default())
        .markdown()
        .contains("| – (nothing touched) |"));
}

#[test]
fn scoring_matches_reports_to_cracks_once_and_counts_decoys_and_misses() {
    let scene = Scene::builtin_default();
    // The default scene: four cracks; a report on the 1 mm crack, a duplicate of it, one on
    // the decoy.
    let r = report_with(&[[37.5, 30.0], [38.0, 30.2], [40.0, 84.0]]);
    let s = score(&scene, &r);
    assert_eq!(s.cracks, 4);
    assert_eq!((s.correct, s.false_reports, s.missed), (1, 2, 3), "{s:?}");
    assert!(s.localisation_mm[0] < 0.5, "{s:?}");
    assert!(s.width_error_mm.is_empty(), "no report carried a width");
    assert!((s.correct_fraction() - 1.0 / 6.0).abs() < 1e-12);
    // A width reported on the 1 mm crack is scored against it; one on the decoy is not.
    let mut r = report_with(&[[37.5, 30.0], [40.0, 84.0]]);
    for c in &mut r.cracks {
        c.width_mm = Some(2.0);
    }
    // An extent 1.5 mm long on the 1 mm crack scores +0.5 mm; the decoy's is not scored.
    for c in &mut r.cracks {
        let [x, y] = c.position_mm;
        c.extent_mm = Some([[x, y - 0.75], [x, y + 0.75]]);
    }
    let s = score(&scene, &r);
    assert_eq!(s.width_error_mm, vec![1.0], "{s:?}");
    assert_eq!(s.extent_width_error_mm.len(), 1, "{s:?}");
    assert!((s.extent_width_error_mm[0] - 0.5).abs() < 1e-12, "{s:?}");
    let none = score(&scene, &report_with(&[]));
    assert_eq!((none.correct, none.missed), (0, 4));
    assert_eq!(none.correct_fraction(), 0.0);
}

#[test]
fn scenes_split_by_how_close_their_lines_come_to_other_features() {
    let crack = |path: Vec<[f64; 2]>, width_mm: f64| Feature::Crack {
        path,
        width_mm,
        depth_mm: 1.0,
        edge_radius_mm: 0.2,
        wall_angle_deg: 90.0,
    };
    let decoy = |path: Vec<[f64; 2]>, width_mm: f64| Feature::Decoy {
        path,
        width_mm,
        reflectivity: 0.4,
    };
    let a = crack(vec![[10.0, 10.0], [50.0, 10.0]], 2.0);
    // Parallel 8 mm higher, 1 mm wide: 8 - 1 - 0.5 = 6.5 mm edge to edge.
    let b = decoy(vec![[10.0, 18.0], [50.0, 18.0]], 1.0);
    assert!((feature_gap_mm(&a, &b).unwrap() - 6.5).abs() < 1e-9);
    // Crossing: 0; the order of the pair does not matter.
    let c = crack(vec![[30.0, 0.0], [30.0, 30.0]], 0.5);
    assert_eq!(feature_gap_mm(&a, &c), Some(0.0));
    assert_eq!(feature_gap_mm(&c, &a), Some(0.0));
    // A screw 10 mm below the crack's line, head 6 mm: 10 - 3 - 1 = 6 mm.
    let screw = Feature::Screw {
        centre: [30.0, 0.0],
        head_diameter_mm: 6.0,
        height_mm: 2.0,
    };
    assert!((feature_gap_mm(&screw, &a).unwrap() - 6.0).abs() < 1e-9);
    // A bump overlapping the line: 0, not negative.
    let bump = Feature::Bump {
        centre: [30.0, 12.0],
        radius_mm: 5.0,
        height_mm: 1.0,
    };
    assert_eq!(feature_gap_mm(&a, &bump), Some(0.0));
    assert_eq!(feature_gap_mm(&screw, &bump), None, "neither is a line");
    // A wavy patch 4 mm below the line (edge 3 mm), and one the line runs through.
    let wavy = |min: [f64; 2], max: [f64; 2]| Feature::Wavy {
        min,
        max,
        amplitude_mm: 0.5,
        period_mm: 5.0,
        direction_deg: 0.0,
    };
    assert!((feature_gap_mm(&a, &wavy([20.0, -10.0], [40.0, 6.0])).unwrap() - 3.0).abs() < 1e-9);
    assert_eq!(
        feature_gap_mm(&a, &wavy([0.0, 0.0], [20.0, 20.0])),
        Some(0.0)
    );
    // A scene's clearance is its smallest gap; one line alone has none.
    let mut scene = Scene::builtin_default();
    scene.features = vec![a.clone()];
    assert_eq!(clearance_mm(&scene), None);
    scene.features = vec![a.clone(), b.clone(), screw.clone()];
    assert!((clearance_mm(&scene).unwrap() - 6.0).abs() < 1e-9);
    scene.features.push(c);
    assert_eq!(clearance_mm(&scene), Some(0.0));
    // Trials split at APART_MM, each group's share the mean over its trials.
    let trial = |seed, clearance_mm, correct, missed| Trial {
        seed,
        cracks: correct + missed,
        decoys: 0,
        vision: Score::default(),
        fused: Score {
            cracks: correct + missed,
            correct,
            missed,
            ..Score::default()
        },
        fused_exploration_s: 10.0,
        finger: FingerBudget::default(),
        clearance_mm,
    };
    let trials = [
        trial(1, None, 1, 0),
        trial(2, Some(APART_MM), 2, 0),
        trial(3, Some(0.0), 1, 1),
        trial(4, Some(4.9), 0, 2),
    ];
    let split = ClearanceSplit::of(&trials);
    assert_eq!((split.apart_scenes, split.close_scenes), (2, 2));
    assert_eq!(split.apart_correct, Some(1.0));
    assert_eq!(split.close_correct, Some(0.25));
    assert_eq!((split.close.correct, split.close.missed), (1, 3));
    let mut t = empty_report(0.5, 0.5, FingerBudget::default());
    assert!(
        t.markdown()
            .contains("(0 of 0 scenes; correct / false / missed) | – | – (no such scene) |"),
        "{}",
        t.markdown()
    );
    t.fused_by_clearance = split;
    assert!(
        t.markdown().contains("| – | 25.0 % (1 / 0 / 3) |"),
        "{}",
        t.markdown()
    );
}
