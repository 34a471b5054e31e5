//! Mission wall time split by stage: whole fused missions on the built-in default scene
//! (`crackbot_mission::inspect::run_inspection`: the simulated controller over the authenticated
//! link on loopback, firmware → PTY → acquisition, the ONNX detector, the planner, the deployed
//! tactile models), at a speed-up of [`SPEEDUP`].
//!
//! * `mission/fused_default_scene`: the whole mission, criterion's sample of 10.
//! * After it, each stage's median over every mission run (`StageTimes`: setup, perception,
//!   planning, exploration, and the rest: classification of the last passes and the report) and
//!   the baseline of the same run: the planner's robot-time estimate of the exploration divided
//!   by the speed-up, i.e. what the arm's motion alone costs; the ratio says what the host adds.
//!
//! `cargo bench --bench mission` (≈ 2 minutes).

use std::sync::atomic::AtomicBool;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use crackbot_mission::inspect::{run_inspection, InspectConfig, StageTimes};
use crackbot_sim::scene::Scene;
use crackbot_testkit::median;
use criterion::{criterion_group, criterion_main, Criterion};

/// Simulation speed-up of the benched missions.
const SPEEDUP: f64 = 16.0;

/// One mission's stage times, its total and the planner's exploration estimate (robot time, s).
struct Run {
    stages: StageTimes,
    total_s: f64,
    planned_s: f64,
}

fn bench_mission(c: &mut Criterion) {
    let out = tempfile::tempdir().expect("a temporary folder");
    let scene = Scene::load_or_default(None).expect("the built-in default scene");
    let mut config = InspectConfig::new(scene, out.path().join("mission"));
    config.rig.speedup = SPEEDUP;
    let config = config.check().expect("the default scene's settings");
    let stop = AtomicBool::new(false);
    let runs: Mutex<Vec<Run>> = Mutex::new(Vec::new());

    let mut group = c.benchmark_group("mission");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(60));
    group.warm_up_time(Duration::from_millis(1));
    group.bench_function("fused_default_scene", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let t = Instant::now();
                let report = run_inspection(&config, &stop, |_| {}).expect("the mission");
                let took = t.elapsed();
                total += took;
                runs.lock().expect("the runs").push(Run {
                    stages: report.stages.clone(),
                    total_s: took.as_secs_f64(),
                    planned_s: report.plan.as_ref().map_or(f64::NAN, |p| p.estimated_s),
                });
            }
            total
        });
    });
    group.finish();

    let runs = runs.into_inner().expect("the runs");
    let col = |f: &dyn Fn(&Run) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
    let total = col(&|r| r.total_s);
    let setup = col(&|r| r.stages.setup_s);
    let perceive = col(&|r| r.stages.perceive_s);
    let plan = col(&|r| r.stages.plan_s);
    let explore = col(&|r| r.stages.explore_s);
    let rest = col(&|r| {
        r.total_s - r.stages.setup_s - r.stages.perceive_s - r.stages.plan_s - r.stages.explore_s
    });
    let floor = col(&|r| r.planned_s / SPEEDUP);
    println!(
        "\nmission stages, medians over {} fused missions on the default scene at speed-up {SPEEDUP}:",
        runs.len()
    );
    println!("| stage | wall ms | share |");
    println!("|---|---|---|");
    for (name, v) in [
        ("setup (controller, sensor, models)", setup),
        ("perception (frame, ONNX detector)", perceive),
        ("planning", plan),
        (
            "exploration (moves, slides, online classification)",
            explore,
        ),
        ("rest (last verdicts, report, recordings)", rest),
        ("total", total),
    ] {
        println!("| {name} | {:.3} | {:.1} % |", 1e3 * v, 100.0 * v / total);
    }
    println!(
        "baseline, same run: the planner's exploration estimate / speed-up = {floor:.3} s; \
         measured exploration / baseline = {:.3}",
        explore / floor
    );
}

criterion_group!(benches, bench_mission);
criterion_main!(benches);
