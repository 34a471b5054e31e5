//! Planner time: a targeted plan (validation, overlap groups, slide fitting, ordering) for 1, 10
//! and 100 random candidates on a 500 × 500 mm wall section, ordered by the default nearest
//! neighbour + 2-opt + Or-opt from 8 starts (`two_opt`), against the baselines in the same run:
//! nearest neighbour alone and the order given; the exact optimum for 8 candidates
//! (`brute_force`, 8! orders); and the tactile-only scan of the paper's 200 × 100 mm plate for
//! γ = 0.25, 0.5, 0.75.
//!
//! `cargo bench --bench planner -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use crackbot_planner::{
    brute_force_order, paper_mean_length_mm, Candidate, Limits, Order, Planner, Settings,
    Workspace, PAPER_EQ1,
};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

/// xorshift64*: the same candidates in every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `n` cracks of 0–60 mm, 0–5 mm wide, anywhere on a `side × side` mm surface.
fn candidates(n: usize, side: f64, seed: u64) -> Vec<Candidate> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|i| Candidate {
            id: i as u64,
            centre_mm: [side * rng.next(), side * rng.next()],
            axis_deg: 180.0 * rng.next(),
            length_mm: 60.0 * rng.next(),
            width_mm: Some(5.0 * rng.next()),
            score: rng.next(),
        })
        .collect()
}

fn targeted(c: &mut Criterion) {
    let ws = Workspace::from_size(500.0, 500.0).expect("workspace");
    let p = Planner::new(ws, Limits::default(), Settings::default()).expect("planner");
    let mut g = c.benchmark_group("planner_targeted");
    for n in [1usize, 10, 100] {
        let cands = candidates(n, 500.0, 0x5EED + n as u64);
        for (name, order) in [
            ("two_opt", Order::TwoOpt),
            ("nearest_neighbour", Order::NearestNeighbour),
            ("as_given", Order::AsGiven),
        ] {
            let plan = p.targeted_with(&cands, order).expect("plan");
            eprintln!(
                "planner_targeted/{name}/{n}: {} slides, {} unreachable, travel {:.1} mm, estimate {:.1} s",
                plan.slides.len(),
                plan.unreachable.len(),
                plan.travel_mm,
                plan.estimated_s
            );
            g.bench_with_input(BenchmarkId::new(name, n), &cands, |b, cands| {
                b.iter(|| p.targeted_with(black_box(cands), order).expect("plan"));
            });
        }
    }
    let eight = candidates(8, 500.0, 0xB00F);
    let best = brute_force_order(&p, &eight).expect("brute force");
    let heuristic = p.targeted(&eight).expect("plan");
    eprintln!(
        "planner_targeted/brute_force/8: travel {:.1} mm (two_opt {:.1} mm)",
        best.travel_mm, heuristic.travel_mm
    );
    g.sample_size(10);
    g.bench_with_input(BenchmarkId::new("brute_force", 8), &eight, |b, cands| {
        b.iter(|| brute_force_order(&p, black_box(cands)).expect("plan"));
    });
    g.finish();
}

fn scan(c: &mut Criterion) {
    let ws = Workspace::from_size(200.0, 100.0).expect("workspace");
    let p = Planner::new(ws, Limits::default(), Settings::default()).expect("planner");
    let l_mm = paper_mean_length_mm(PAPER_EQ1.mean_length_px, PAPER_EQ1.camera_height_px, 100.0);
    let mut g = c.benchmark_group("planner_tactile_scan");
    for gamma in [0.25, 0.5, 0.75] {
        g.bench_with_input(BenchmarkId::from_parameter(gamma), &gamma, |b, &gamma| {
            b.iter(|| p.tactile_scan(black_box(gamma), l_mm).expect("scan"));
        });
    }
    g.finish();
}

criterion_group!(benches, targeted, scan);
criterion_main!(benches);
