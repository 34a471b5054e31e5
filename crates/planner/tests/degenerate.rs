//! Degenerate inputs give a plan or a clear error: an empty scene, a candidate on the workspace
//! edge or outside it, overlapping candidates (slid one by one or merged), a zero-length crack,
//! non-finite coordinates, duplicate ids, γ out of range, speeds above the limits.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use crackbot_planner::{
    brute_force_order, targeted, Candidate, Limits, OnUnreachable, Order, Overlap, Plan, PlanError,
    PlanKind, Planner, RaisedPass, Settings, Workspace, MAX_BRUTE_FORCE,
};

fn plate() -> Workspace {
    Workspace::from_size(200.0, 100.0).unwrap()
}

fn planner(settings: Settings) -> Planner {
    Planner::new(plate(), Limits::default(), settings).unwrap()
}

fn crack(id: u64, x: f64, y: f64, axis_deg: f64, length: f64, width: f64) -> Candidate {
    Candidate {
        id,
        centre_mm: [x, y],
        axis_deg,
        length_mm: length,
        width_mm: Some(width),
        score: 0.9,
    }
}

/// Every slide and move inside the workspace, speeds within the limits, the totals consistent.
fn check(plan: &Plan, limits: &Limits) {
    let ws = plan.workspace;
    for s in &plan.slides {
        assert!(ws.contains(s.start_mm) && ws.contains(s.end_mm), "{s:?}");
        assert!(s.speed_mm_s <= limits.max_slide_speed_mm_s);
        assert!(s.stroke_mm > 0.0);
        if let Some(run) = s.sound_run_mm {
            assert!(run[0] >= 2.0 - 1e-9 && run[1] >= 2.0 - 1e-9, "{s:?}");
        }
    }
    for m in &plan.moves {
        assert!(ws.contains(m.from_mm) && ws.contains(m.to_mm), "{m:?}");
        assert!(m.speed_mm_s <= limits.max_travel_speed_mm_s);
    }
    let t = plan.time;
    assert!((t.travel_s + t.slide_s + t.settle_s + t.raised_s - t.total_s).abs() < 1e-9);
    assert_eq!(plan.estimated_s, t.total_s);
}

#[test]
fn an_empty_scene_is_an_empty_plan() {
    let p = planner(Settings::default());
    for order in [
        Order::AsGiven,
        Order::NearestNeighbour,
        Order::TwoOpt,
        Order::BruteForce,
    ] {
        let plan = p.targeted_with(&[], order).unwrap();
        assert!(plan.slides.is_empty() && plan.moves.is_empty() && plan.unreachable.is_empty());
        assert_eq!((plan.travel_mm, plan.estimated_s), (0.0, 0.0));
        assert_eq!(plan.end_mm, plan.start_mm);
    }
    let ret = planner(Settings {
        return_to_start: true,
        ..Settings::default()
    });
    assert!(ret.targeted(&[]).unwrap().moves.is_empty());
}

#[test]
fn one_crack_in_the_open_gets_one_centred_slide_across_it() {
    let p = planner(Settings::default());
    let plan = p
        .targeted(&[crack(7, 100.0, 50.0, 0.0, 40.0, 2.0)])
        .unwrap();
    check(&plan, p.limits());
    assert_eq!(plan.slides.len(), 1);
    let s = &plan.slides[0];
    assert!(s.is_as_asked());
    assert_eq!(s.candidates, vec![7]);
    // Perpendicular to the axis (along y), through the centre, 1 + 4.4 + 10 mm each side.
    assert!((s.start_mm[0] - 100.0).abs() < 1e-9 && (s.end_mm[0] - 100.0).abs() < 1e-9);
    assert!((s.stroke_mm - 2.0 * 15.4).abs() < 1e-9, "{s:?}");
    let run = s.sound_run_mm.unwrap();
    assert!((run[0] - 10.0).abs() < 1e-9 && (run[1] - 10.0).abs() < 1e-9);
    // Entered at the end nearer the start pose (0, 0): the lower one.
    assert!(s.start_mm[1] < s.end_mm[1]);
    // Forth and back at the paper's speed.
    assert_eq!((s.passes, s.speed_mm_s), (2, 3.89));
    assert!((s.duration_s - (2.0 * 30.8 / 3.89 + 0.05)).abs() < 1e-9);
    assert!((plan.travel_mm - (100.0f64.powi(2) + 34.6f64.powi(2)).sqrt()).abs() < 1e-9);
}

#[test]
fn a_candidate_on_the_edge_is_shifted_clipped_moved_or_reported() {
    let p = planner(Settings::default());
    // Centre on the bottom edge, crack along x: a slide along y would need 1 + 4.4 + 2 mm below
    // the crack's centre line, outside the workspace, and the crack has no length to move along.
    let along_edge = crack(1, 100.0, 0.0, 0.0, 0.0, 2.0);
    let plan = p.targeted(std::slice::from_ref(&along_edge)).unwrap();
    check(&plan, p.limits());
    assert!(plan.slides.is_empty());
    assert_eq!(plan.unreachable.len(), 1);
    assert_eq!(plan.unreachable[0].candidates, vec![1]);
    assert!(
        plan.unreachable[0]
            .reason
            .contains("no slide across it fits"),
        "{:?}",
        plan.unreachable
    );
    // The same, refused.
    let strict = planner(Settings {
        on_unreachable: OnUnreachable::Error,
        ..Settings::default()
    });
    let e = strict.targeted(&[along_edge]).unwrap_err();
    assert!(
        matches!(&e, PlanError::Unreachable { ids, .. } if ids == &vec![1]),
        "{e}"
    );

    // 8 mm from the bottom edge: 8 − 1 − 4.4 = 2.6 mm of sound surface fit below; the slide is
    // shifted up to keep its full length.
    let near = crack(2, 100.0, 8.0, 0.0, 30.0, 2.0);
    let plan = p.targeted(&[near]).unwrap();
    check(&plan, p.limits());
    let s = &plan.slides[0];
    assert!(!s.clipped && s.shifted_mm > 0.0, "{s:?}");
    assert!((s.stroke_mm - 30.8).abs() < 1e-9);
    let run = s.sound_run_mm.unwrap();
    assert!((run[0] - 2.6).abs() < 1e-9, "{run:?}");
    assert!((run[1] - 17.4).abs() < 1e-9, "{run:?}");

    // A crack running out of the workspace across the bottom edge: slid where it is inside.
    let crossing = crack(3, 100.0, 0.0, 90.0, 40.0, 2.0);
    let plan = p.targeted(&[crossing]).unwrap();
    check(&plan, p.limits());
    assert_eq!(plan.slides.len(), 1);
    assert!(plan.slides[0].is_as_asked(), "{:?}", plan.slides[0]);
    assert!(plan.slides[0].start_mm[1].abs() < 1e-9);

    // A long crack 3 mm from the bottom edge and parallel to it: no point of it leaves room
    // below, so moving along it does not help: reported.
    let plan = p.targeted(&[crack(4, 100.0, 3.0, 0.0, 60.0, 2.0)]).unwrap();
    assert_eq!(plan.unreachable.len(), 1);

    // A diagonal crack whose centre is off the plate but whose end is on it: moved along it.
    let off = Candidate::from_axis(5, [[-20.0, 20.0], [20.0, 60.0]], Some(1.0), 0.5);
    let plan = p.targeted(&[off]).unwrap();
    check(&plan, p.limits());
    assert_eq!(plan.slides.len(), 1);
    assert!(plan.slides[0].moved_along_mm > 0.0, "{:?}", plan.slides[0]);

    // Far outside: reported.
    let plan = p
        .targeted(&[crack(6, 500.0, 500.0, 0.0, 10.0, 1.0)])
        .unwrap();
    assert_eq!(plan.unreachable.len(), 1);
    assert!(plan.slides.is_empty());
}

#[test]
fn a_narrow_workspace_clips_the_stroke() {
    // 20 mm tall: a 30.8 mm slide along y is cut to 20 mm, leaving 20/2 − 1 − 4.4 = 4.6 mm.
    let ws = Workspace::new(0.0, 200.0, 0.0, 20.0).unwrap();
    let p = Planner::new(ws, Limits::default(), Settings::default()).unwrap();
    let plan = p.targeted(&[crack(1, 50.0, 10.0, 0.0, 30.0, 2.0)]).unwrap();
    check(&plan, p.limits());
    let s = &plan.slides[0];
    assert!(s.clipped && (s.stroke_mm - 20.0).abs() < 1e-9, "{s:?}");
    let run = s.sound_run_mm.unwrap();
    assert!((run[0] - 4.6).abs() < 1e-9 && (run[1] - 4.6).abs() < 1e-9);
    // 12 mm tall: 6 − 1 − 4.4 = 0.6 mm < 2 mm: unreachable.
    let ws = Workspace::new(0.0, 200.0, 0.0, 12.0).unwrap();
    let p = Planner::new(ws, Limits::default(), Settings::default()).unwrap();
    assert_eq!(
        p.targeted(&[crack(1, 50.0, 6.0, 0.0, 30.0, 2.0)])
            .unwrap()
            .unreachable
            .len(),
        1
    );
}

#[test]
fn overlapping_candidates_are_both_slid_or_merged() {
    // A crack labelled as a chain of two overlapping boxes, and a third, separate one.
    let chain = [
        crack(1, 60.0, 50.0, 30.0, 30.0, 2.0),
        crack(2, 82.0, 62.0, 30.0, 30.0, 2.0),
        crack(3, 160.0, 30.0, 90.0, 20.0, 1.0),
    ];
    let both = planner(Settings::default()).targeted(&chain).unwrap();
    check(&both, &Limits::default());
    assert_eq!(both.overlapping, vec![vec![1, 2]]);
    assert_eq!(both.slides.len(), 3);
    let mut ids: Vec<u64> = both
        .slides
        .iter()
        .flat_map(|s| s.candidates.clone())
        .collect();
    ids.sort_unstable();
    assert_eq!(ids, vec![1, 2, 3]);

    let merged = planner(Settings {
        overlap: Overlap::Merge,
        ..Settings::default()
    })
    .targeted(&chain)
    .unwrap();
    check(&merged, &Limits::default());
    assert_eq!(merged.overlapping, vec![vec![1, 2]]);
    assert_eq!(merged.slides.len(), 2);
    let m = merged
        .slides
        .iter()
        .find(|s| s.candidates.len() == 2)
        .unwrap();
    assert_eq!(m.candidates, vec![1, 2]);
    // Across the merged crack's centre, perpendicular to the common axis.
    let mid = [
        (m.start_mm[0] + m.end_mm[0]) / 2.0,
        (m.start_mm[1] + m.end_mm[1]) / 2.0,
    ];
    assert!(
        (mid[0] - 71.0).abs() < 1e-6 && (mid[1] - 56.0).abs() < 1e-6,
        "{mid:?}"
    );
    let d = [m.end_mm[0] - m.start_mm[0], m.end_mm[1] - m.start_mm[1]];
    let axis = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
    assert!((d[0] * axis[0] + d[1] * axis[1]).abs() < 1e-6);
    assert!(merged.estimated_s < both.estimated_s);

    // Identical candidates (two detections of one crack) with different ids.
    let twins = [
        crack(8, 100.0, 50.0, 0.0, 10.0, 1.0),
        crack(9, 100.0, 50.0, 0.0, 10.0, 1.0),
    ];
    let plan = planner(Settings::default()).targeted(&twins).unwrap();
    assert_eq!(
        (plan.slides.len(), plan.overlapping.clone()),
        (2, vec![vec![8, 9]])
    );
    // The second costs no travel: it starts where the first ended.
    assert_eq!(plan.moves[1].length_mm, 0.0);
}

#[test]
fn a_zero_length_crack_is_slid_across_once() {
    let p = planner(Settings {
        along_spacing_mm: Some(5.0),
        ..Settings::default()
    });
    let mut c = crack(1, 100.0, 50.0, 45.0, 0.0, 0.0);
    c.width_mm = None; // assumed 10 mm
    let plan = p.targeted(&[c]).unwrap();
    check(&plan, p.limits());
    assert_eq!(plan.slides.len(), 1);
    assert!((plan.slides[0].stroke_mm - 2.0 * (5.0 + 4.4 + 10.0)).abs() < 1e-9);
    // A zero-width, zero-length one: still at least the paper's 16 mm stroke... and the margin.
    let plan = p.targeted(&[crack(2, 100.0, 50.0, 0.0, 0.0, 0.0)]).unwrap();
    assert!((plan.slides[0].stroke_mm - 28.8).abs() < 1e-9);
    let short = planner(Settings {
        margin_mm: 2.0,
        ..Settings::default()
    });
    let plan = short
        .targeted(&[crack(2, 100.0, 50.0, 0.0, 0.0, 0.0)])
        .unwrap();
    assert!((plan.slides[0].stroke_mm - 16.0).abs() < 1e-9);
    // Spaced slides along a long crack: ceil(40 / 5) = 8, serpentine, all different places.
    let plan = p
        .targeted(&[crack(3, 100.0, 50.0, 0.0, 40.0, 1.0)])
        .unwrap();
    check(&plan, p.limits());
    assert_eq!(plan.slides.len(), 8);
    let xs: Vec<f64> = plan.slides.iter().map(|s| s.start_mm[0]).collect();
    assert!(xs.windows(2).all(|w| (w[1] - w[0]).abs() > 4.99), "{xs:?}");
}

#[test]
fn non_finite_or_negative_fields_are_refused_naming_the_candidate_and_field() {
    let p = planner(Settings::default());
    let ok = crack(1, 10.0, 10.0, 0.0, 5.0, 1.0);
    let cases: Vec<(Candidate, &str)> = vec![
        (
            Candidate {
                centre_mm: [f64::NAN, 1.0],
                ..ok.clone()
            },
            "centre_mm[0]",
        ),
        (
            Candidate {
                centre_mm: [1.0, f64::INFINITY],
                ..ok.clone()
            },
            "centre_mm[1]",
        ),
        (
            Candidate {
                centre_mm: [1e12, 1.0],
                ..ok.clone()
            },
            "centre_mm[0]",
        ),
        (
            Candidate {
                axis_deg: f64::NEG_INFINITY,
                ..ok.clone()
            },
            "axis_deg",
        ),
        (
            Candidate {
                length_mm: -1.0,
                ..ok.clone()
            },
            "length_mm",
        ),
        (
            Candidate {
                length_mm: f64::NAN,
                ..ok.clone()
            },
            "length_mm",
        ),
        (
            Candidate {
                width_mm: Some(-0.5),
                ..ok.clone()
            },
            "width_mm",
        ),
        (
            Candidate {
                width_mm: Some(f64::INFINITY),
                ..ok.clone()
            },
            "width_mm",
        ),
        (
            Candidate {
                score: f64::NAN,
                ..ok.clone()
            },
            "score",
        ),
    ];
    for (bad, field) in cases {
        let bad = Candidate { id: 42, ..bad };
        let e = p.targeted(&[ok.clone(), bad]).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("candidate 42") && text.contains("#1") && text.contains(field),
            "{text}"
        );
    }
    let e = p.targeted(&[ok.clone(), ok.clone()]).unwrap_err();
    assert_eq!(
        e,
        PlanError::DuplicateCandidate {
            id: 1,
            first: 0,
            second: 1
        }
    );
}

#[test]
fn settings_and_limits_are_checked_once() {
    let ws = plate();
    let lim = Limits::default();
    let err = |s: Settings| Planner::new(ws, lim, s).unwrap_err().to_string();
    assert!(err(Settings {
        slide_speed_mm_s: 11.0,
        ..Settings::default()
    })
    .contains(
        "settings.slide_speed_mm_s = 11 mm/s is above the limit limits.max_slide_speed_mm_s = 10"
    ));
    assert!(err(Settings {
        travel_speed_mm_s: 500.0,
        ..Settings::default()
    })
    .contains("limits.max_travel_speed_mm_s"));
    assert!(err(Settings {
        slide_speed_mm_s: f64::NAN,
        ..Settings::default()
    })
    .contains("settings.slide_speed_mm_s"));
    assert!(err(Settings {
        slide_speed_mm_s: 0.0,
        ..Settings::default()
    })
    .contains("settings.slide_speed_mm_s"));
    assert!(err(Settings {
        passes: 0,
        ..Settings::default()
    })
    .contains("settings.passes"));
    assert!(err(Settings {
        min_margin_mm: 20.0,
        ..Settings::default()
    })
    .contains("settings.min_margin_mm"));
    assert!(err(Settings {
        reach_mm: 0.0,
        min_margin_mm: 0.0,
        ..Settings::default()
    })
    .contains("start and end off the crack"));
    assert!(err(Settings {
        travel_accel_mm_s2: Some(-1.0),
        ..Settings::default()
    })
    .contains("travel_accel"));
    assert!(err(Settings {
        along_spacing_mm: Some(0.0),
        ..Settings::default()
    })
    .contains("along_spacing"));
    let raised = |overrun_mm: f64, speed_mm_s: f64| Settings {
        raised_pass: Some(RaisedPass {
            overrun_mm,
            speed_mm_s,
        }),
        ..Settings::default()
    };
    assert!(err(raised(1.5, 500.0)).contains(
        "settings.raised_pass.speed_mm_s = 500 mm/s is above the limit limits.max_travel_speed_mm_s"
    ));
    assert!(err(raised(1.5, 0.0)).contains("settings.raised_pass.speed_mm_s"));
    assert!(err(raised(-1.0, 40.0)).contains("settings.raised_pass.overrun_mm"));
    assert!(err(raised(f64::NAN, 40.0)).contains("settings.raised_pass.overrun_mm"));
    assert!(err(Settings {
        start_mm: Some([-1.0, 0.0]),
        ..Settings::default()
    })
    .contains("start pose"));
    assert!(err(Settings {
        start_mm: Some([f64::NAN, 0.0]),
        ..Settings::default()
    })
    .contains("start pose"));
    let e = Planner::new(
        ws,
        Limits {
            max_slide_speed_mm_s: -1.0,
            ..lim
        },
        Settings::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("limits.max_slide_speed_mm_s"), "{e}");
    let bad_ws = Workspace {
        x_min_mm: 5.0,
        x_max_mm: 1.0,
        y_min_mm: 0.0,
        y_max_mm: 1.0,
    };
    let e = Planner::new(bad_ws, lim, Settings::default()).unwrap_err();
    assert!(e.to_string().contains("workspace.x_max_mm"), "{e}");
    // Exactly at the limits is allowed.
    let at = Settings {
        slide_speed_mm_s: 10.0,
        travel_speed_mm_s: 100.0,
        ..Settings::default()
    };
    assert!(targeted(ws, lim, at, &[crack(1, 100.0, 50.0, 0.0, 5.0, 1.0)]).is_ok());
}

#[test]
fn gamma_out_of_range_is_an_error_and_the_scan_covers_the_plate() {
    let p = planner(Settings::default());
    for g in [0.0, 1.0, -0.1, 2.0, f64::NAN] {
        let e = p.tactile_scan(g, 30.85).unwrap_err();
        assert!(e.to_string().contains("gamma"), "{e}");
    }
    assert!(p
        .tactile_scan(0.5, 0.0)
        .unwrap_err()
        .to_string()
        .contains("mean_length"));
    assert!(matches!(
        p.tactile_scan(0.5, 1e-6),
        Err(PlanError::TooManyRows { .. })
    ));
    let plan = p.tactile_scan(0.75, 30.85).unwrap();
    check(&plan, p.limits());
    let PlanKind::TactileScan {
        rows,
        row_spacing_mm,
        crossing_guaranteed,
        ..
    } = plan.kind
    else {
        panic!("{:?}", plan.kind)
    };
    assert_eq!((rows, row_spacing_mm, crossing_guaranteed), (5, 25.0, true));
    // Boustrophedon: rows alternate, bottom edge to top edge, whole width.
    let ys: Vec<f64> = plan.slides.iter().map(|s| s.start_mm[1]).collect();
    assert_eq!(ys, vec![0.0, 25.0, 50.0, 75.0, 100.0]);
    for (k, s) in plan.slides.iter().enumerate() {
        assert_eq!(s.row, Some(k));
        assert_eq!(s.stroke_mm, 200.0);
        assert_eq!(s.start_mm[0], if k % 2 == 0 { 0.0 } else { 200.0 });
    }
    assert_eq!(plan.travel_mm, 100.0);
    // A long crack: one row across the middle.
    let one = p.tactile_scan(0.5, 300.0).unwrap();
    assert_eq!(one.slides.len(), 1);
    assert_eq!(one.slides[0].start_mm, [0.0, 50.0]);
    // Started from the top-right corner, it sweeps from there.
    let tr = planner(Settings {
        start_mm: Some([200.0, 100.0]),
        ..Settings::default()
    });
    let plan = tr.tactile_scan(0.75, 30.85).unwrap();
    assert_eq!(plan.slides[0].start_mm, [200.0, 100.0]);
    assert_eq!(plan.slides[4].start_mm[1], 0.0);
    assert_eq!(plan.moves[0].length_mm, 0.0);
}

#[test]
fn brute_force_is_limited_to_small_cases() {
    let p = planner(Settings::default());
    let many: Vec<Candidate> = (0..=MAX_BRUTE_FORCE as u64)
        .map(|i| crack(i, 10.0 + 20.0 * i as f64, 50.0, 0.0, 5.0, 1.0))
        .collect();
    let e = brute_force_order(&p, &many).unwrap_err();
    assert_eq!(
        e,
        PlanError::TooManyForBruteForce {
            n: MAX_BRUTE_FORCE + 1,
            max: MAX_BRUTE_FORCE
        }
    );
    assert!(brute_force_order(&p, &many[..MAX_BRUTE_FORCE]).is_ok());
}

#[test]
fn plans_serialise() {
    let p = planner(Settings::default());
    let plan = p
        .targeted(&[crack(1, 100.0, 50.0, 0.0, 40.0, 2.0)])
        .unwrap();
    let json = serde_json::to_value(&plan).unwrap();
    assert_eq!(json["kind"]["kind"], "targeted");
    assert_eq!(json["kind"]["order"], "two_opt");
    assert_eq!(json["slides"][0]["candidates"][0], 1);
    let settings: Settings =
        serde_json::from_str(r#"{"slide_speed_mm_s": 4.6, "overlap": "merge"}"#).unwrap();
    assert_eq!(
        (settings.slide_speed_mm_s, settings.overlap, settings.passes),
        (4.6, Overlap::Merge, 2)
    );
    assert!(serde_json::from_str::<Settings>(r#"{"slide_speed": 4.6}"#).is_err());
    // Settings written before the reach was named keep their meaning.
    let old: Settings = serde_json::from_str(r#"{"tip_radius_mm": 2.5}"#).unwrap();
    assert_eq!(old.reach_mm, 2.5);
    let new: Settings = serde_json::from_str(r#"{"reach_mm": 2.5}"#).unwrap();
    assert_eq!(new, old);
}

/// A raised pass over every targeted slide (the mission's print check): from the overrun behind
/// the end where the strokes left the finger to the overrun beyond the other end, clamped to the
/// workspace; its time joins the estimate and the next move starts where it ends. Scan rows get
/// none.
#[test]
fn raised_passes_follow_each_targeted_slide_and_count_in_the_estimate() {
    let pass = RaisedPass {
        overrun_mm: 1.5,
        speed_mm_s: 40.0,
    };
    let cracks = [
        crack(1, 50.0, 50.0, 90.0, 20.0, 2.0),
        crack(2, 150.0, 40.0, 0.0, 30.0, 1.0),
        // Across the workspace's left edge: the pass is clamped there.
        crack(3, 1.0, 80.0, 90.0, 10.0, 1.0),
    ];
    let without = planner(Settings::default()).targeted(&cracks).unwrap();
    let with = planner(Settings {
        raised_pass: Some(pass),
        ..Settings::default()
    })
    .targeted(&cracks)
    .unwrap();
    check(&with, &Limits::default());
    assert_eq!(without.time.raised_s, 0.0);
    assert!(without.raised.is_empty());
    assert_eq!(with.raised.len(), 2 * with.slides.len());
    let ws = plate();
    for (sl, m) in with.slides.iter().zip(with.raised.chunks(2)) {
        // Two passes: the strokes leave the finger at the start; it backs off behind it and
        // flies past the end.
        let u = [
            (sl.end_mm[0] - sl.start_mm[0]) / sl.stroke_mm,
            (sl.end_mm[1] - sl.start_mm[1]) / sl.stroke_mm,
        ];
        let behind = ws.clamp([sl.start_mm[0] - 1.5 * u[0], sl.start_mm[1] - 1.5 * u[1]]);
        let beyond = ws.clamp([sl.end_mm[0] + 1.5 * u[0], sl.end_mm[1] + 1.5 * u[1]]);
        assert_eq!(m[0].from_mm, sl.start_mm);
        for (a, b) in [
            (m[0].to_mm, behind),
            (m[1].from_mm, behind),
            (m[1].to_mm, beyond),
        ] {
            assert!(
                (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
                "{a:?} {b:?}"
            );
        }
        assert!(m.iter().all(|m| m.speed_mm_s == 40.0));
        assert!((m[1].duration_s - m[1].length_mm / 40.0).abs() < 1e-12);
        assert!(m[1].length_mm <= sl.stroke_mm + 3.0 + 1e-9);
        assert!(m[1].length_mm > sl.stroke_mm);
    }
    let sum: f64 = with.raised.iter().map(|m| m.duration_s).sum();
    assert!((with.time.raised_s - sum).abs() < 1e-12);
    assert!(with.time.raised_s > 0.0);
    assert_eq!(with.time.slide_s, without.time.slide_s);
    // The whole pass is inside the workspace even where the slide touches its edge.
    assert!(with.raised.iter().all(|m| ws.contains(m.to_mm)));
    // A scan has no candidates to check.
    let scan = planner(Settings {
        raised_pass: Some(pass),
        ..Settings::default()
    })
    .tactile_scan(0.5, 40.0)
    .unwrap();
    assert!(scan.raised.is_empty() && scan.time.raised_s == 0.0);
}
