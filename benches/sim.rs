//! Simulator speed: simulated seconds per wall second of the finger (one slide over a 5 mm
//! crack at the default integrator, and at the reference accuracy), and camera rendering time
//! per frame of the default scene. `cargo bench --bench sim`; `python3 benches/summary.py`.

use std::time::Duration;

use crackbot_sim::render::{render, CrackAssets, RenderOptions};
use crackbot_sim::run::{SlideSim, SAMPLE_RATE_HZ};
use crackbot_sim::work_precision::{run_slide, slide};
use crackbot_sim::{Integrator, Scene};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

fn finger(c: &mut Criterion) {
    let mut g = c.benchmark_group("sim_finger_slide");
    g.sample_size(20).measurement_time(Duration::from_secs(8));
    // One slide = 2 × (16 mm / 3.89 mm/s + ramp) ≈ 8.3 simulated seconds; the throughput is
    // reported in simulated milliseconds (elements) per second.
    for (name, method) in [
        ("sdirk2_x1_default", Integrator::default()),
        (
            "dopri5_rtol1e-6_reference",
            Integrator::DormandPrince {
                rtol: 1e-6,
                atol: 1e-9,
            },
        ),
    ] {
        let (values, _, _) = run_slide(method).expect("slide");
        g.throughput(Throughput::Elements((values.len() as f64 * 2.5) as u64));
        // Stepping only: building the slide (profile and the tip's envelope, ~3 ms for the
        // 10 mm tip) happens once per recording and is measured separately below.
        g.bench_function(name, |b| {
            b.iter_batched(
                || slide(method).expect("slide"),
                |mut sim: SlideSim| {
                    let n = (sim.slide_time() * SAMPLE_RATE_HZ).round() as usize;
                    for _ in 0..n {
                        sim.next_sample().expect("sample");
                    }
                    sim
                },
                BatchSize::PerIteration,
            );
        });
    }
    g.bench_function("setup_profile_and_envelope", |b| {
        b.iter(|| slide(Integrator::default()).expect("slide"));
    });
    g.finish();
}

fn camera(c: &mut Criterion) {
    let scene = Scene::builtin_default();
    let Ok(assets) = CrackAssets::load_default() else {
        eprintln!("crack photos not found: skipping the rendering bench");
        return;
    };
    let mut g = c.benchmark_group("sim_render");
    g.sample_size(20).measurement_time(Duration::from_secs(8));
    let mut seed = 0;
    g.bench_function("default_scene_640x480", |b| {
        b.iter(|| {
            seed += 1;
            render(&scene, &assets, &RenderOptions::default(), seed).expect("frame")
        });
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = finger, camera
}
criterion_main!(benches);
