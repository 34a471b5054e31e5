//! How far the ordering heuristic is from the optimum: random scenes of 2 to 8 candidates on the
//! paper's 200 × 100 mm plate, travel of nearest neighbour alone and of nearest neighbour +
//! 2-opt + Or-opt (the default) against the exact optimum of `brute_force_order`, for the
//! default forth-and-back slides, one-way slides (which end on the other side) and several
//! slides along each crack. Prints the worst and mean ratios (`--nocapture`).

use crackbot_planner::{brute_force_order, Candidate, Limits, Order, Planner, Settings, Workspace};

/// xorshift64*: a fixed, dependency-free stream of uniform numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn scene(rng: &mut Rng, n: usize) -> Vec<Candidate> {
    (0..n)
        .map(|i| Candidate {
            id: i as u64,
            centre_mm: [15.0 + 170.0 * rng.next(), 15.0 + 70.0 * rng.next()],
            axis_deg: 180.0 * rng.next(),
            length_mm: 40.0 * rng.next(),
            width_mm: Some(5.0 * rng.next()),
            score: rng.next(),
        })
        .collect()
}

struct Stats {
    worst: f64,
    sum: f64,
    n: usize,
    optimal: usize,
}

impl Stats {
    fn new() -> Self {
        Stats {
            worst: 1.0,
            sum: 0.0,
            n: 0,
            optimal: 0,
        }
    }
    fn add(&mut self, ratio: f64) {
        self.worst = self.worst.max(ratio);
        self.sum += ratio;
        self.n += 1;
        if ratio <= 1.0 + 1e-9 {
            self.optimal += 1;
        }
    }
    fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }
}

#[test]
fn the_heuristic_is_close_to_the_brute_force_optimum() {
    let ws = Workspace::from_size(200.0, 100.0).unwrap();
    let cases = [
        ("forth and back (default)", Settings::default()),
        (
            "one-way slides",
            Settings {
                passes: 1,
                ..Settings::default()
            },
        ),
        (
            "slides every 10 mm along",
            Settings {
                along_spacing_mm: Some(10.0),
                ..Settings::default()
            },
        ),
        (
            "back to the start",
            Settings {
                return_to_start: true,
                ..Settings::default()
            },
        ),
    ];
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    println!("| slides | cases | NN + 2-opt worst | mean | optimal | NN only worst | mean |");
    println!("|---|---|---|---|---|---|---|");
    for (name, settings) in cases {
        let p = Planner::new(ws, Limits::default(), settings).unwrap();
        let (mut two, mut nn) = (Stats::new(), Stats::new());
        for k in 0..150 {
            let n = 2 + k % 7;
            let cands = scene(&mut rng, n);
            let best = brute_force_order(&p, &cands).unwrap();
            assert!(best.unreachable.is_empty());
            let h = p.targeted(&cands).unwrap();
            let g = p.targeted_with(&cands, Order::NearestNeighbour).unwrap();
            // Same slides, other order: the estimates differ by travel only.
            assert_eq!(h.slides.len(), best.slides.len());
            assert!((h.slide_mm - best.slide_mm).abs() < 1e-6);
            assert!(
                best.travel_mm <= h.travel_mm + 1e-6,
                "brute force lost: {} > {}",
                best.travel_mm,
                h.travel_mm
            );
            two.add(h.travel_mm / best.travel_mm);
            nn.add(g.travel_mm / best.travel_mm);
        }
        println!(
            "| {name} | {} | {:.4} | {:.4} | {}/{} | {:.4} | {:.4} |",
            two.n,
            two.worst,
            two.mean(),
            two.optimal,
            two.n,
            nn.worst,
            nn.mean()
        );
        assert!(two.worst <= 1.05, "{name}: worst ratio {}", two.worst);
        assert!(two.mean() <= 1.005, "{name}: mean ratio {}", two.mean());
        assert!(two.mean() <= nn.mean());
    }
}
