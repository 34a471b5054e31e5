//! Deterministic synthetic data shaped like the tactile MAV features (ADC counts ~200–1000, 0.1
//! resolution), for tests, examples and benchmarks.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::data::{Dataset, RegressionDataset};
use crate::error::Result;

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn adc(v: f64) -> f32 {
    ((v.clamp(0.0, 1023.0) * 10.0).round() / 10.0) as f32
}

/// Overlapping Gaussian blobs: `n_classes` centres drawn in `[350, 850]` per feature, isotropic standard
/// deviation `spread` ADC counts, classes assigned round-robin, values rounded to 0.1 and clamped to
/// `[0, 1023]`.
pub fn blobs(
    n_rows: usize,
    n_features: usize,
    n_classes: usize,
    spread: f64,
    seed: u64,
) -> Result<Dataset> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let centres: Vec<f64> = (0..n_classes * n_features)
        .map(|_| rng.random_range(350.0..850.0))
        .collect();
    let mut x = Vec::with_capacity(n_rows * n_features);
    let mut y = Vec::with_capacity(n_rows);
    for i in 0..n_rows {
        let c = i % n_classes.max(1);
        for f in 0..n_features {
            x.push(adc(centres[c * n_features + f] + spread * normal(&mut rng)));
        }
        y.push(c as u32);
    }
    Dataset::with_classes(x, n_features, y, n_classes.max(1))
}

/// A regression set: three ADC-like features uniform in `[200, 1000]` and a width-like target
/// `y = 5 + 3·sin(x0 / 80) + 0.004·(x1 − 600) + noise·N(0, 1)` (values around 1–9 "mm").
pub fn width_regression(n_rows: usize, noise: f64, seed: u64) -> Result<RegressionDataset> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut x = Vec::with_capacity(n_rows * 3);
    let mut y = Vec::with_capacity(n_rows);
    for _ in 0..n_rows {
        let row: [f32; 3] = [
            adc(rng.random_range(200.0..1000.0)),
            adc(rng.random_range(200.0..1000.0)),
            adc(rng.random_range(200.0..1000.0)),
        ];
        x.extend_from_slice(&row);
        y.push(width_function(&row) + (noise * normal(&mut rng)) as f32);
    }
    RegressionDataset::new(x, 3, y)
}

/// The noise-free target of [`width_regression`].
pub fn width_function(x: &[f32]) -> f32 {
    let x0 = x.first().copied().unwrap_or(0.0) as f64;
    let x1 = x.get(1).copied().unwrap_or(0.0) as f64;
    (5.0 + 3.0 * (x0 / 80.0).sin() + 0.004 * (x1 - 600.0)) as f32
}
