//! Times single-row and batch prediction of a 100-tree forest trained on synthetic MAV-like data.
//!
//! `cargo run -p crackbot-research --release --example predict_timing -- [train_rows] [trees] [batch_rows]`
//! (defaults: 75000, 100, 200000). Prediction runs on one core.

use std::time::Instant;

use crackbot_forest::{synthetic, Classifier, ForestParams, RandomForest};

fn arg<T: std::str::FromStr>(i: usize) -> Option<T> {
    std::env::args().nth(i).and_then(|s| s.parse().ok())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rows: usize = arg(1).unwrap_or(75_000);
    let trees: usize = arg(2).unwrap_or(100);
    let batch: usize = arg(3).unwrap_or(200_000);
    let train = synthetic::blobs(rows, 3, 4, 60.0, 42)?;
    let forest = RandomForest::fit(
        &train,
        &ForestParams::classifier()
            .n_trees(trees)
            .seed(1)
            .quiet(true),
    )?;
    println!(
        "forest: {} trees, {:.0} nodes/tree, max depth {}, {:.1} MB of nodes",
        forest.n_trees(),
        forest.n_nodes() as f64 / trees as f64,
        forest.max_depth(),
        forest.n_nodes() as f64 * 12.0 / 1e6
    );
    let test = synthetic::blobs(batch, 3, 4, 60.0, 4242)?;
    let x = test.x();
    println!(
        "mean path length: {:.1} nodes per tree and row",
        mean_path(&forest, &x[..3 * 2000.min(batch)])
    );

    // Single rows: median and p99 of per-call latency over random rows.
    let n_single = 20_000.min(batch);
    let mut lat = Vec::with_capacity(n_single);
    let mut sink = 0u64;
    for i in 0..n_single {
        let row = &x[i * 3..i * 3 + 3];
        let t0 = Instant::now();
        sink += forest.predict(row) as u64;
        lat.push(t0.elapsed().as_nanos() as f64);
    }
    let mean = lat.iter().sum::<f64>() / lat.len() as f64;
    lat.sort_by(f64::total_cmp);
    println!(
        "single row predict: median {:.2} µs, mean {:.2} µs, p99 {:.2} µs ({n_single} rows, timer included)",
        lat[lat.len() / 2] / 1e3,
        mean / 1e3,
        lat[lat.len() * 99 / 100] / 1e3
    );
    let mut proba = [0f32; 4];
    let t0 = Instant::now();
    for i in 0..n_single {
        forest.predict_proba_into(&x[i * 3..i * 3 + 3], &mut proba);
        sink += (proba[0] > 0.5) as u64;
    }
    println!(
        "single row predict_proba_into: {:.2} µs/row (loop)",
        t0.elapsed().as_secs_f64() * 1e6 / n_single as f64
    );

    // Batch.
    let mut out = vec![0u32; batch];
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t0 = Instant::now();
        forest.predict_batch(x, 3, &mut out)?;
        best = best.min(t0.elapsed().as_secs_f64());
    }
    println!(
        "predict_batch: {batch} rows in {:.3} s (best of 3) = {:.2} M rows/s on one core",
        best,
        batch as f64 / best / 1e6
    );
    let agree = (0..batch)
        .filter(|&i| out[i] == forest.predict(&x[i * 3..i * 3 + 3]))
        .count();
    println!("batch == single on {agree}/{batch} rows (sink {sink})");
    Ok(())
}

/// Mean number of internal nodes visited per tree and row.
fn mean_path(forest: &RandomForest, x: &[f32]) -> f64 {
    let (nodes, offsets) = (forest.nodes(), forest.tree_offsets());
    let mut steps = 0usize;
    let rows = x.chunks_exact(3);
    let n_rows = rows.len();
    for row in rows {
        for &root in &offsets[..forest.n_trees()] {
            let mut i = root as usize;
            while !nodes[i].is_leaf() {
                let n = nodes[i];
                i = if row[n.feature as usize] <= n.threshold {
                    i + 1
                } else {
                    n.right as usize
                };
                steps += 1;
            }
        }
    }
    steps as f64 / (n_rows * forest.n_trees()) as f64
}
