//! Nothing outside the workspace or above the speed limits is ever planned: random workspaces,
//! settings and candidates (inside, on the edge, outside, overlapping, zero-length, huge), every
//! slide endpoint and every travel waypoint inside, every speed within the limits, every
//! candidate either slid across (from sound surface to sound surface) or reported.
#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use crackbot_planner::{
    Candidate, Limits, Order, Overlap, Plan, PlanError, PlanKind, Planner, RaisedPass, Settings,
    Workspace,
};
use proptest::prelude::*;

fn workspace() -> impl Strategy<Value = Workspace> {
    (
        -500.0..500.0f64,
        1.0..1000.0f64,
        -500.0..500.0f64,
        1.0..1000.0f64,
    )
        .prop_map(|(x, w, y, h)| Workspace::new(x, x + w, y, y + h).unwrap())
}

fn limits() -> impl Strategy<Value = Limits> {
    (0.5..50.0f64, 5.0..500.0f64).prop_map(|(s, t)| Limits {
        max_slide_speed_mm_s: s,
        max_travel_speed_mm_s: t,
    })
}

/// Settings under `limits`, starting inside `ws`.
fn settings(ws: Workspace, limits: Limits) -> impl Strategy<Value = Settings> {
    (
        (
            0.01..=1.0f64,
            0.01..=1.0f64,
            prop::option::of(10.0..2000.0f64),
        ),
        (0.0..3.0f64, 0.0..0.5f64, 1u32..4, 1u32..3),
        (
            0.0..20.0f64,
            0.0..=1.0f64,
            0.0..10.0f64,
            0.0..40.0f64,
            0.0..20.0f64,
        ),
        (
            prop::option::of(1.0..50.0f64),
            prop_oneof![Just(Overlap::SlideBoth), Just(Overlap::Merge)],
            prop_oneof![
                Just(Order::AsGiven),
                Just(Order::NearestNeighbour),
                Just(Order::TwoOpt)
            ],
            any::<bool>(),
            (0.0..=1.0f64, 0.0..=1.0f64),
            prop::option::of((0.0..5.0f64, 0.01..=1.0f64)),
        ),
    )
        .prop_map(
            move |(
                (fs, ft, accel),
                (settle, reversal, passes, scan_passes),
                (margin, min_frac, tip, min_stroke, assumed),
                (spacing, overlap, order, ret, (u, v), raised),
            )| Settings {
                slide_speed_mm_s: fs * limits.max_slide_speed_mm_s,
                travel_speed_mm_s: ft * limits.max_travel_speed_mm_s,
                travel_accel_mm_s2: accel,
                settle_s: settle,
                reversal_s: reversal,
                passes,
                scan_passes,
                margin_mm: margin,
                min_margin_mm: min_frac * margin,
                // Keep tip + min margin > 0 (checked by Planner::new).
                reach_mm: tip.max(0.01),
                min_stroke_mm: min_stroke,
                assumed_width_mm: assumed,
                along_spacing_mm: spacing,
                overlap,
                order,
                on_unreachable: Default::default(),
                start_mm: Some([
                    ws.x_min_mm + u * ws.width_mm(),
                    ws.y_min_mm + v * ws.height_mm(),
                ]),
                return_to_start: ret,
                raised_pass: raised.map(|(overrun, f)| RaisedPass {
                    overrun_mm: overrun,
                    speed_mm_s: f * limits.max_travel_speed_mm_s,
                }),
            },
        )
}

/// Candidates around `ws`: a quarter of its size beyond each edge, some exactly on an edge,
/// some zero-length, some repeated (overlapping).
fn candidates(ws: Workspace) -> impl Strategy<Value = Vec<Candidate>> {
    let one = (
        (-0.25..1.25f64, -0.25..1.25f64, 0u8..5),
        -360.0..360.0f64,
        prop_oneof![Just(0.0), 0.0..300.0f64],
        prop::option::of(prop_oneof![Just(0.0), 0.0..50.0f64]),
        0.0..1.0f64,
    )
        .prop_map(move |((u, v, snap), axis, length, width, score)| {
            let mut c = [
                ws.x_min_mm + u * ws.width_mm(),
                ws.y_min_mm + v * ws.height_mm(),
            ];
            match snap {
                0 => c[0] = ws.x_min_mm,
                1 => c[1] = ws.y_max_mm,
                _ => {}
            }
            (c, axis, length, width, score)
        });
    prop::collection::vec(one, 0..12).prop_map(|v| {
        let mut out: Vec<Candidate> = v
            .into_iter()
            .enumerate()
            .map(|(i, (c, axis, length, width, score))| Candidate {
                id: 100 + i as u64,
                centre_mm: c,
                axis_deg: axis,
                length_mm: length,
                width_mm: width,
                score,
            })
            .collect();
        // A twin of the first (a second detection of the same crack).
        if let Some(first) = out.first().cloned() {
            out.push(Candidate { id: 999, ..first });
        }
        out
    })
}

fn assert_safe(plan: &Plan, ws: &Workspace, limits: &Limits, s: &Settings) {
    for sl in &plan.slides {
        assert!(
            ws.contains(sl.start_mm) && ws.contains(sl.end_mm),
            "slide outside {ws}: {sl:?}"
        );
        assert!(
            sl.speed_mm_s > 0.0 && sl.speed_mm_s <= limits.max_slide_speed_mm_s,
            "{sl:?}"
        );
        assert!(sl.stroke_mm.is_finite() && sl.stroke_mm >= 0.0);
        assert!(sl.duration_s.is_finite() && sl.duration_s >= 0.0);
        if let Some(run) = sl.sound_run_mm {
            assert!(
                run[0] >= s.min_margin_mm - 1e-6 && run[1] >= s.min_margin_mm - 1e-6,
                "{sl:?}"
            );
            assert!(sl.stroke_mm > 0.0);
        }
    }
    // Moves and raised passes alike: inside, under the travel limit.
    for m in plan.moves.iter().chain(&plan.raised) {
        assert!(
            ws.contains(m.from_mm) && ws.contains(m.to_mm),
            "move outside {ws}: {m:?}"
        );
        assert!(
            m.speed_mm_s > 0.0 && m.speed_mm_s <= limits.max_travel_speed_mm_s,
            "{m:?}"
        );
        assert!(m.duration_s.is_finite() && m.duration_s >= 0.0);
    }
    // The moves chain the slides: start → slide 0 (→ its raised pass) → … (→ start).
    assert!(plan.moves.len() == plan.slides.len() || plan.moves.len() == plan.slides.len() + 1);
    let mut at = plan.start_mm;
    let mut raised = plan.raised.chunks(2);
    for (k, sl) in plan.slides.iter().enumerate() {
        assert_eq!(plan.moves[k].from_mm, at);
        assert_eq!(plan.moves[k].to_mm, sl.start_mm);
        at = sl.exit_mm();
        if s.raised_pass.is_some() && !sl.candidates.is_empty() {
            let pass = raised
                .next()
                .expect("a raised pass for every targeted slide");
            assert_eq!(pass[0].from_mm, at);
            assert_eq!(pass[0].to_mm, pass[1].from_mm);
            at = pass[1].to_mm;
        }
    }
    assert!(raised.next().is_none(), "a raised pass without its slide");
    if plan.moves.len() > plan.slides.len() {
        assert_eq!(plan.moves.last().map(|m| m.to_mm), Some(plan.start_mm));
    }
    let t = plan.time;
    assert!(
        t.total_s.is_finite()
            && (t.travel_s + t.slide_s + t.settle_s + t.raised_s - t.total_s).abs()
                <= 1e-9 * t.total_s.max(1.0)
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn targeted_plans_stay_inside_and_under_the_limits(
        (ws, limits, s, cands) in (workspace(), limits()).prop_flat_map(|(ws, lim)| {
            (Just(ws), Just(lim), settings(ws, lim), candidates(ws))
        })
    ) {
        let planner = Planner::new(ws, limits, s.clone()).unwrap();
        let plan = planner.targeted(&cands).unwrap();
        assert_safe(&plan, &ws, &limits, &s);
        // Every candidate is slid across or reported, never both, never lost.
        let mut slid: Vec<u64> = plan.slides.iter().flat_map(|sl| sl.candidates.clone()).collect();
        slid.sort_unstable();
        slid.dedup();
        let mut reported: Vec<u64> = plan.unreachable.iter().flat_map(|u| u.candidates.clone()).collect();
        reported.sort_unstable();
        let mut all: Vec<u64> = cands.iter().map(|c| c.id).collect();
        all.sort_unstable();
        let mut both = slid.clone();
        both.extend(&reported);
        both.sort_unstable();
        prop_assert_eq!(both, all);
        // Slides of one candidate run perpendicular to its axis.
        for sl in plan.slides.iter().filter(|sl| sl.candidates.len() == 1 && sl.stroke_mm > 1e-6) {
            let c = cands.iter().find(|c| c.id == sl.candidates[0]).unwrap();
            let a = c.axis();
            let d = [sl.end_mm[0] - sl.start_mm[0], sl.end_mm[1] - sl.start_mm[1]];
            prop_assert!((d[0] * a[0] + d[1] * a[1]).abs() <= 1e-6 * sl.stroke_mm.max(1.0), "{:?} {:?}", sl, c);
        }
        // The heuristic never travels further than nearest neighbour alone.
        if s.order == Order::TwoOpt {
            let nn = planner.targeted_with(&cands, Order::NearestNeighbour).unwrap();
            prop_assert!(plan.travel_mm <= nn.travel_mm + 1e-6, "{} > {}", plan.travel_mm, nn.travel_mm);
        }
    }

    #[test]
    fn scans_stay_inside_and_under_the_limits(
        (ws, limits, s, gamma, length) in (workspace(), limits()).prop_flat_map(|(ws, lim)| {
            (Just(ws), Just(lim), settings(ws, lim), 0.01..0.99f64, 0.5..2000.0f64)
        })
    ) {
        let planner = Planner::new(ws, limits, s.clone()).unwrap();
        match planner.tactile_scan(gamma, length) {
            Ok(plan) => {
                assert_safe(&plan, &ws, &limits, &s);
                let PlanKind::TactileScan { rows, row_spacing_mm, .. } = plan.kind else {
                    panic!("not a scan")
                };
                prop_assert_eq!(rows, plan.slides.len());
                prop_assert!(rows == 1 || row_spacing_mm >= gamma * length * (1.0 - 1e-12));
            }
            Err(e) => prop_assert!(matches!(e, PlanError::TooManyRows { .. }), "{}", e),
        }
    }
}
