//! Times forest training on synthetic data shaped like the tactile MAV windows.
//!
//! `cargo run -p crackbot-research --release --example train_timing -- [rows] [trees] [threads] [spread]`
//! (defaults: 75000 rows × 3 features, 4 classes, 100 trees, rayon's default threads, spread 60).

use std::time::Instant;

use crackbot_forest::{accuracy, synthetic, ForestParams, RandomForest};

fn arg<T: std::str::FromStr>(i: usize) -> Option<T> {
    std::env::args().nth(i).and_then(|s| s.parse().ok())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rows: usize = arg(1).unwrap_or(75_000);
    let trees: usize = arg(2).unwrap_or(100);
    let threads: Option<usize> = arg(3);
    let spread: f64 = arg(4).unwrap_or(60.0);
    let data = synthetic::blobs(rows + rows / 3, 3, 4, spread, 42)?;
    let (train, test) = data.split_at(rows)?;
    let params = ForestParams::classifier()
        .n_trees(trees)
        .seed(1)
        .n_threads(threads);
    let t0 = Instant::now();
    let forest = RandomForest::fit(&train, &params)?;
    let dt = t0.elapsed();
    println!(
        "trained {trees} trees on {rows} rows × 3 features ({} threads): {:.3} s ({:.1} ms/tree/thread); \
         {:.0} nodes/tree, max depth {}; test accuracy {:.3}; importances {:?}",
        threads.unwrap_or_else(rayon_threads),
        dt.as_secs_f64(),
        dt.as_secs_f64() * 1e3 * threads.unwrap_or_else(rayon_threads) as f64 / trees as f64,
        forest.n_nodes() as f64 / trees as f64,
        forest.max_depth(),
        accuracy(&forest, &test),
        forest.feature_importances().unwrap_or(&[]),
    );
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZero::get)
}
