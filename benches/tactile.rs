//! Tactile inference on one core, on the authors' real recordings (surface-type experiment, MAV of D1, D2,
//! P over 10-sample windows every 2 samples; forests trained on repetition 1, windows of repetition 2):
//!
//! * `per_window/*`: per-window latency of the streaming feature update (`StreamingFeatures::push`, the
//!   `step` pushes that end a window), of a 100-tree `RandomForest::predict` on a real window, and of both
//!   together — what the robot pays per window at 400 Hz.
//! * `batch/predict_batch`: `RandomForest::predict_batch` over all windows of repetition 2, in windows/s.
//! * `linfa/*`: the baseline in the same run. linfa cannot load our model, so a 100-tree linfa forest is
//!   trained on the same windows (bagged CART trees, every feature, depth ≤ [`LINFA_MAX_DEPTH`], first
//!   [`LINFA_MAX_ROWS`] training windows: linfa trains one tree after another and takes seconds per fully
//!   grown tree) and converted into our flat model (`benches/common/linfa_forest.rs`; the conversion is
//!   checked by `tests/linfa_flat_conversion.rs`). linfa's own `predict` and our flat predict then run on
//!   that same forest and the same windows, one row at a time and as a batch.
//!
//! * `onnx_runtime/*`: ONNX Runtime in the same run, on the same forest and windows: the forest file is
//!   exported to ONNX (`scripts/forest_to_onnx.sh`, a `TreeEnsembleClassifier` / `TreeEnsembleRegressor`)
//!   and run by ONNX Runtime (`ort`, one intra-op thread) next to our flat predict, one row at a time
//!   and as one batch. The forest is the 100-tree forest above (trained again, identical), or any forest
//!   file (classifier or regressor) given by `CRACKBOT_BENCH_FOREST`, with its windows from
//!   `CRACKBOT_BENCH_WINDOWS` (a CSV: header, then the model's features in the first columns; the real
//!   windows of repetition 2 when unset and the model has their 3 features). A deployed tactile model
//!   (`CRKTACTL`, e.g. `models/tactile/recognition.ctm`) is read too: the forest of section
//!   `CRACKBOT_BENCH_SECTION` (default `context_forest`; `window_forest` takes the real windows). With
//!   `CRACKBOT_BENCH_FOREST` set, only this group runs. The bench first asserts that ONNX Runtime's probabilities (or values)
//!   match ours to 1e-6 and its class is ours on every window.
//!
//! `taskset -c 1 cargo bench --bench tactile` (medians and ratios: `python3 benches/summary.py`).

use std::hint::black_box;

use crackbot_dsp::StreamingFeatures;
use crackbot_forest::{Classifier, ForestParams, RandomForest};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use linfa::prelude::Predict;

#[path = "common/linfa_forest.rs"]
mod linfa_forest;
#[path = "common/onnx_forest.rs"]
mod onnx_forest;
#[path = "common/windows.rs"]
mod windows;

/// Trees in every forest of this bench (the paper's forest).
const N_TREES: usize = 100;
/// Depth caps of the `per_window_depth_capped` forests.
const DEPTH_CAPS: [usize; 3] = [8, 10, 12];
/// Windows timed one by one for the latency tail.
const TAIL_WINDOWS: usize = 200_000;
/// Depth cap of the linfa forest (its training time; see the module docs).
const LINFA_MAX_DEPTH: usize = 20;
/// Training windows given to linfa.
const LINFA_MAX_ROWS: usize = 20_000;

/// A stream of real samples feeding [`StreamingFeatures`], wrapping around at the end.
struct Stream<'a> {
    features: StreamingFeatures,
    samples: &'a [[f64; 4]],
    next: usize,
    row: [f32; 3],
}

impl<'a> Stream<'a> {
    fn new(samples: &'a [[f64; 4]]) -> Self {
        let cfg = windows::config();
        Self {
            features: StreamingFeatures::new(cfg.spec, cfg.window).expect("streaming features"),
            samples,
            next: 0,
            row: [0.0; 3],
        }
    }

    /// Pushes samples until a window ends; returns its feature row.
    #[inline]
    fn next_window(&mut self) -> &[f32; 3] {
        loop {
            let s = self.samples[self.next];
            self.next += 1;
            if self.next == self.samples.len() {
                self.next = 0;
            }
            if let Some(r) = self.features.push(s).expect("finite sample") {
                self.row.copy_from_slice(r);
                return &self.row;
            }
        }
    }
}

#[expect(
    clippy::too_many_lines,
    reason = "one criterion group per stage, set up in order"
)]
fn bench(c: &mut Criterion) {
    if std::env::var_os("CRACKBOT_BENCH_FOREST").is_some() {
        eprintln!("CRACKBOT_BENCH_FOREST is set: only the onnx_runtime group runs, on that forest");
        return;
    }
    let real = windows::load(&windows::data_dir());
    let nf = real.test.n_features;
    let n_test = real.test.n_rows();
    let n_classes = real.test.experiment.n_classes();
    let train = crackbot_forest::Dataset::with_classes(
        real.train.x.clone(),
        nf,
        real.train.y.clone(),
        n_classes,
    )
    .expect("training set");
    let forest = RandomForest::fit(
        &train,
        &ForestParams::classifier()
            .n_trees(N_TREES)
            .seed(1)
            .quiet(true),
    )
    .expect("forest");
    eprintln!(
        "windows: {} train (repetition 1), {n_test} test (repetition 2); our forest: {} trees, {} nodes, depth {}",
        real.train.n_rows(),
        forest.n_trees(),
        forest.n_nodes(),
        forest.max_depth()
    );

    let mut g = c.benchmark_group("per_window");
    g.throughput(Throughput::Elements(1));
    let mut stream = Stream::new(&real.test_samples);
    g.bench_function("stream_push", |b| {
        b.iter(|| black_box(*stream.next_window()));
    });
    let mut i = 0;
    g.bench_function("forest_predict", |b| {
        b.iter(|| {
            i = if i + 1 == n_test { 0 } else { i + 1 };
            forest.predict(black_box(real.test.row(i)))
        });
    });
    let mut stream = Stream::new(&real.test_samples);
    g.bench_function("stream_push+forest_predict", |b| {
        b.iter(|| {
            let row = *stream.next_window();
            forest.predict(black_box(&row))
        });
    });
    g.finish();

    // Depth-capped forests of the same 100 trees: what a depth limit buys in latency, with its
    // accuracy on the same test windows printed beside it (`crackbot tactile tradeoff` has the
    // full table).
    let accuracy = |f: &RandomForest| {
        let right = (0..n_test)
            .filter(|&r| f.predict(real.test.row(r)) == real.test.y[r])
            .count();
        100.0 * right as f64 / n_test as f64
    };
    eprintln!(
        "accuracy (repetition 1 → 2), fully grown: {:.2}%",
        accuracy(&forest)
    );
    let mut capped_forests = Vec::new();
    let mut g = c.benchmark_group("per_window_depth_capped");
    g.throughput(Throughput::Elements(1));
    for depth in DEPTH_CAPS {
        let capped = RandomForest::fit(
            &train,
            &ForestParams::classifier()
                .n_trees(N_TREES)
                .max_depth(Some(depth))
                .seed(1)
                .quiet(true),
        )
        .expect("forest");
        eprintln!(
            "depth ≤ {depth}: {} nodes, accuracy (repetition 1 → 2) {:.2}%",
            capped.n_nodes(),
            accuracy(&capped)
        );
        let mut stream = Stream::new(&real.test_samples);
        g.bench_function(format!("depth{depth}/stream_push+forest_predict"), |b| {
            b.iter(|| {
                let row = *stream.next_window();
                capped.predict(black_box(&row))
            });
        });
        capped_forests.push((depth, capped));
    }
    g.finish();

    // Criterion reports central values; the tail comes from timing windows one by one (each
    // timing includes the clock read, ~20–30 ns).
    let tail = |name: &str, f: &RandomForest| {
        let mut stream = Stream::new(&real.test_samples);
        let mut ns: Vec<u128> = (0..TAIL_WINDOWS)
            .map(|_| {
                let t = std::time::Instant::now();
                let row = *stream.next_window();
                black_box(f.predict(black_box(&row)));
                t.elapsed().as_nanos()
            })
            .collect();
        ns.sort_unstable();
        let q = |p: f64| ns[((ns.len() - 1) as f64 * p) as usize] as f64 / 1000.0;
        eprintln!(
            "{name}: stream_push+forest_predict over {TAIL_WINDOWS} windows one by one: median {:.2} µs, p99 {:.2} µs, p99.9 {:.2} µs",
            q(0.5),
            q(0.99),
            q(0.999)
        );
    };
    tail("fully grown", &forest);
    for (depth, f) in &capped_forests {
        tail(&format!("depth ≤ {depth}"), f);
    }

    let mut out = vec![0u32; n_test];
    let mut g = c.benchmark_group("batch");
    g.throughput(Throughput::Elements(n_test as u64));
    g.sample_size(20);
    g.bench_function("predict_batch", |b| {
        b.iter(|| {
            forest
                .predict_batch(black_box(&real.test.x), nf, &mut out)
                .expect("batch");
            black_box(&out);
        });
    });
    for (depth, f) in &capped_forests {
        g.bench_function(format!("depth{depth}/predict_batch"), |b| {
            b.iter(|| {
                f.predict_batch(black_box(&real.test.x), nf, &mut out)
                    .expect("batch");
                black_box(&out);
            });
        });
    }
    g.finish();

    let t0 = std::time::Instant::now();
    let rf = linfa_forest::train_linfa(
        &real.train,
        N_TREES,
        Some(LINFA_MAX_DEPTH),
        LINFA_MAX_ROWS,
        1,
    );
    let flat = linfa_forest::linfa_to_flat(&rf, nf, n_classes);
    let records = linfa_forest::records(&real.test.x, nf);
    let linfa_pred = rf.predict(&records);
    let differ: Vec<usize> = (0..n_test)
        .filter(|&r| flat.predict(real.test.row(r)) as usize != linfa_pred[r])
        .collect();
    let not_ties = differ
        .iter()
        .filter(|&&r| !linfa_forest::linfa_tie(&rf, real.test.row(r)))
        .count();
    assert_eq!(
        not_ties, 0,
        "the converted forest differs from linfa off vote ties"
    );
    eprintln!(
        "linfa forest: trained in {:.1} s on {} windows, {} trees, {} nodes, depth {}; the converted model \
         differs from linfa on {}/{n_test} windows, all exact vote ties",
        t0.elapsed().as_secs_f64(),
        real.train.n_rows().min(LINFA_MAX_ROWS),
        flat.n_trees(),
        flat.n_nodes(),
        flat.max_depth(),
        differ.len()
    );
    let single: Vec<_> = (0..n_test)
        .map(|r| linfa_forest::records(real.test.row(r), nf))
        .collect();
    let mut g = c.benchmark_group("linfa_forest");
    g.throughput(Throughput::Elements(1));
    let mut i = 0;
    g.bench_function("linfa_predict_row", |b| {
        b.iter(|| {
            i = if i + 1 == n_test { 0 } else { i + 1 };
            rf.predict(black_box(&single[i]))
        });
    });
    let mut i = 0;
    g.bench_function("flat_predict_row", |b| {
        b.iter(|| {
            i = if i + 1 == n_test { 0 } else { i + 1 };
            flat.predict(black_box(real.test.row(i)))
        });
    });
    g.throughput(Throughput::Elements(n_test as u64));
    g.sample_size(10);
    g.bench_function("linfa_predict_batch", |b| {
        b.iter(|| rf.predict(black_box(&records)));
    });
    g.bench_function("flat_predict_batch", |b| {
        b.iter(|| {
            flat.predict_batch(black_box(&real.test.x), nf, &mut out)
                .expect("batch");
            black_box(&out);
        });
    });
    g.finish();
}

/// Our forest and ONNX Runtime on the same forest file and windows (see the module docs).
fn onnx_runtime(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let onnx = dir.path().join("tactile.onnx");
    let mut exported = false;
    let (forest_path, x) = match std::env::var_os("CRACKBOT_BENCH_FOREST") {
        Some(p) => {
            let mut path = std::path::PathBuf::from(p);
            if onnx_forest::is_tactile_model(&path) {
                // A deployed model: one of its forests, as a plain forest file for our side.
                let section = std::env::var("CRACKBOT_BENCH_SECTION")
                    .unwrap_or_else(|_| "context_forest".into());
                let forest = dir.path().join(format!("{section}.forest"));
                onnx_forest::export_section(&path, &section, &onnx, &forest)
                    .unwrap_or_else(|e| panic!("{e}"));
                eprintln!("onnx_runtime: section {section} of {}", path.display());
                path = forest;
                exported = true;
            }
            let ours = onnx_forest::Ours::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let x = match std::env::var_os("CRACKBOT_BENCH_WINDOWS") {
                Some(csv) => onnx_forest::read_windows_csv(csv.as_ref(), ours.n_features())
                    .unwrap_or_else(|e| panic!("CRACKBOT_BENCH_WINDOWS: {e}")),
                None => {
                    let real = windows::load(&windows::data_dir());
                    assert_eq!(
                        ours.n_features(),
                        real.test.n_features,
                        "{} has {} features, the real windows {}: set CRACKBOT_BENCH_WINDOWS to a CSV of its windows",
                        path.display(),
                        ours.n_features(),
                        real.test.n_features
                    );
                    real.test.x
                }
            };
            (path, x)
        }
        None => {
            let real = windows::load(&windows::data_dir());
            let train = crackbot_forest::Dataset::with_classes(
                real.train.x.clone(),
                real.train.n_features,
                real.train.y.clone(),
                real.train.experiment.n_classes(),
            )
            .expect("training set");
            let forest = RandomForest::fit(
                &train,
                &ForestParams::classifier()
                    .n_trees(N_TREES)
                    .seed(1)
                    .quiet(true),
            )
            .expect("forest");
            let path = dir.path().join("tactile.forest");
            forest.save(&path).expect("save the forest");
            (path, real.test.x)
        }
    };
    let ours = onnx_forest::Ours::load(&forest_path).unwrap_or_else(|e| panic!("{e}"));
    let nf = ours.n_features();
    let n = x.len() / nf;
    if !exported {
        onnx_forest::export(&forest_path, &onnx).unwrap_or_else(|e| panic!("{e}"));
    }
    let mut ort = onnx_forest::OrtForest::load(&onnx, nf, 1).unwrap_or_else(|e| panic!("{e}"));
    let a = onnx_forest::compare(&ours, &mut ort, &x).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        a.max_diff <= 1e-6 && a.class_differs.is_empty(),
        "ONNX Runtime differs from ours on {}: max |Δ| {}, class on {} of {n} windows",
        forest_path.display(),
        a.max_diff,
        a.class_differs.len()
    );
    eprintln!(
        "onnx_runtime: {} ({}), {n} windows; ONNX Runtime matches ours (max |Δ| {:.1e}, same class on every window)",
        forest_path.display(),
        ours.describe(),
        a.max_diff
    );

    let mut g = c.benchmark_group("onnx_runtime");
    g.throughput(Throughput::Elements(1));
    let mut i = 0;
    match &ours {
        onnx_forest::Ours::Classifier(f) => g.bench_function("ours_row", |b| {
            b.iter(|| {
                i = if i + 1 == n { 0 } else { i + 1 };
                f.predict(black_box(&x[i * nf..(i + 1) * nf]))
            });
        }),
        onnx_forest::Ours::Regressor(f) => g.bench_function("ours_row", |b| {
            b.iter(|| {
                i = if i + 1 == n { 0 } else { i + 1 };
                f.predict(black_box(&x[i * nf..(i + 1) * nf]))
            });
        }),
    };
    let mut i = 0;
    g.bench_function("onnxruntime_row", |b| {
        b.iter(|| {
            i = if i + 1 == n { 0 } else { i + 1 };
            ort.run_one(black_box(&x[i * nf..(i + 1) * nf]))
        });
    });
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(10);
    match &ours {
        onnx_forest::Ours::Classifier(f) => {
            let mut out = vec![0u32; n];
            g.bench_function("ours_batch", |b| {
                b.iter(|| {
                    f.predict_batch(black_box(&x), nf, &mut out).expect("batch");
                    black_box(&out);
                });
            })
        }
        onnx_forest::Ours::Regressor(f) => {
            let mut out = vec![0f32; n];
            g.bench_function("ours_batch", |b| {
                b.iter(|| {
                    f.predict_batch(black_box(&x), nf, &mut out).expect("batch");
                    black_box(&out);
                });
            })
        }
    };
    g.bench_function("onnxruntime_batch", |b| {
        b.iter(|| ort.run(black_box(&x)).expect("ONNX Runtime batch"));
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: criterion's plotters backend panics without a system font (FontUnavailable) here.
    config = Criterion::default().without_plots();
    targets = bench, onnx_runtime
}
criterion_main!(benches);
