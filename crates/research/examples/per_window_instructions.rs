//! The per-window path of the robot (streaming MAV D1D2+P update + 100-tree forest prediction), run `N`
//! times for an instruction count under callgrind: `scripts/callgrind_check.sh` (run by `.ci/run`).
//!
//! * `per_window_instructions prepare DIR`: trains the forest (100 trees, seed 1) on the real windows of
//!   repetition 1 and writes it to `DIR/forest.bin`, with the raw samples of repetition 2 in
//!   `DIR/samples.bin`. Run natively: training under valgrind would take minutes.
//! * `per_window_instructions measure DIR N`: loads both and runs `N` windows through
//!   [`per_window_loop`], the only function callgrind counts (`--collect-atstart=no
//!   --toggle-collect=*per_window_loop*`), so loading is not counted.
//!
//! Everything is deterministic (fixed data, fixed seed, training independent of the thread count), so the
//! count only moves when the code or the compiler does.

use std::hint::black_box;
use std::path::{Path, PathBuf};

use crackbot_dsp::StreamingFeatures;
use crackbot_forest::{Classifier, Dataset, ForestParams, RandomForest};

#[path = "../../../benches/common/windows.rs"]
mod windows;

/// Samples of repetition 2 kept for the measurement (the loop wraps around).
const SAMPLES: usize = 50_000;

fn prepare(dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let real = windows::load(&windows::data_dir());
    let n_classes = real.train.experiment.n_classes();
    let train = Dataset::with_classes(
        real.train.x.clone(),
        real.train.n_features,
        real.train.y.clone(),
        n_classes,
    )?;
    let params = ForestParams::classifier().n_trees(100).seed(1).quiet(true);
    let forest = RandomForest::fit(&train, &params)?;
    forest.save(dir.join("forest.bin"))?;
    let bytes: Vec<u8> = real
        .test_samples
        .iter()
        .take(SAMPLES)
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(dir.join("samples.bin"), bytes)?;
    println!(
        "forest: {} trees, {} nodes, depth {} ({} training windows); {} samples",
        forest.n_trees(),
        forest.n_nodes(),
        forest.max_depth(),
        real.train.n_rows(),
        real.test_samples.len().min(SAMPLES)
    );
    Ok(())
}

/// Streams samples through the feature update and classifies each window; returns a checksum of the
/// classes. The function callgrind counts: keep its name (`scripts/callgrind_check.sh`).
#[inline(never)]
fn per_window_loop(
    stream: &mut StreamingFeatures,
    forest: &RandomForest,
    samples: &[[f64; 4]],
    n_windows: usize,
) -> u64 {
    let mut sum = 0u64;
    let mut done = 0;
    let mut i = 0;
    while done < n_windows {
        let s = samples[i];
        i = if i + 1 == samples.len() { 0 } else { i + 1 };
        if let Ok(Some(row)) = stream.push(s) {
            sum = sum * 31 + u64::from(forest.predict(black_box(row)));
            done += 1;
        }
    }
    sum
}

fn measure(dir: &Path, n: usize) -> Result<(), Box<dyn std::error::Error>> {
    let forest = RandomForest::load(dir.join("forest.bin"))?;
    let bytes = std::fs::read(dir.join("samples.bin"))?;
    let samples: Vec<[f64; 4]> = bytes
        .chunks_exact(32)
        .map(|c| {
            let mut s = [0.0; 4];
            for (v, b) in s.iter_mut().zip(c.chunks_exact(8)) {
                *v = f64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
            }
            s
        })
        .collect();
    if samples.is_empty() {
        return Err("no samples".into());
    }
    let cfg = windows::config();
    let mut stream = StreamingFeatures::new(cfg.spec, cfg.window)?;
    let sum = per_window_loop(&mut stream, &forest, &samples, n);
    println!("{n} windows, checksum {sum}");
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["prepare", dir] => prepare(&PathBuf::from(dir)),
        ["measure", dir, n] => measure(&PathBuf::from(dir), n.parse()?),
        _ => Err("usage: per_window_instructions prepare DIR | measure DIR N (see scripts/callgrind_check.sh)".into()),
    }
}
