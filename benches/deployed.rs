//! The deployed tactile path on one core: what the robot pays per window with the committed
//! model (`models/tactile/recognition.ctm`, or `CRACKBOT_BENCH_MODEL`), on the authors' real
//! recordings (surface-type experiment, repetition 2).
//!
//! * `deployed/per_window`: two samples into [`OnlineClassifier::push`] — the context features
//!   (`StreamingContext`), the paper's window features, both rows kept for the slide verdict, and
//!   the running verdict (context forest + window forest) of the window the second sample ends.
//!   Slides begin where the recording's slides do, so the per-slide work is included, amortised.
//!   The bench also times 200 000 windows one by one and prints the median, p99 and p99.9
//!   (criterion gives central values only).
//! * `deployed/batch`: both forests' `predict_proba_batch` over every window of repetition 2
//!   (features already computed), in windows/s.
//!
//! `taskset -c 1 cargo bench --bench deployed`.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

use crackbot_recording::{collect_recordings, Recording};
use crackbot_tactile::dataset::Experiment;
use crackbot_tactile::model::TactileModel;
use crackbot_tactile::online::OnlineClassifier;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

/// Windows timed one by one for the latency tail.
const TAIL_WINDOWS: usize = 200_000;

fn model_path() -> PathBuf {
    match std::env::var_os("CRACKBOT_BENCH_MODEL") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models/tactile/recognition.ctm"),
    }
}

fn recordings() -> Vec<(PathBuf, Recording)> {
    let dir = crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE);
    let all = collect_recordings(&[dir]).expect("the surface-type recordings");
    all.into_iter()
        .filter(|(p, _)| p.to_string_lossy().ends_with("_2.mat"))
        .collect()
}

/// Real samples with slide starts, cycled.
struct Feed {
    rows: Vec<([f64; 4], u8, f64, bool)>,
    next: usize,
}

impl Feed {
    fn new(recs: &[(PathBuf, Recording)]) -> Self {
        let mut rows = Vec::new();
        for (_, rec) in recs {
            for range in rec.slides() {
                for (i, r) in rec.rows[range].iter().enumerate() {
                    rows.push((r.channels(), r.direction, r.x_mm, i == 0));
                }
            }
        }
        Feed { rows, next: 0 }
    }

    /// Pushes samples until one returns a running verdict (one window).
    #[inline]
    fn window(&mut self, online: &mut OnlineClassifier<'_>) {
        loop {
            let (s, d, x, start) = self.rows[self.next];
            self.next = (self.next + 1) % self.rows.len();
            if start {
                online.begin_slide();
            }
            if let Ok(Some(v)) = online.push(s, d, x) {
                black_box(v);
                return;
            }
        }
    }
}

fn bench(c: &mut Criterion) {
    let path = model_path();
    let model = TactileModel::load(&path)
        .unwrap_or_else(|e| panic!("{e} (train it: crackbot tactile train, see models/tactile)"));
    let recs = recordings();
    let mut feed = Feed::new(&recs);
    let mut online = OnlineClassifier::new(&model).expect("an online classifier");
    // Warm up over every slide once (the buffers reach the longest slide's size).
    for _ in 0..feed.rows.len() / 2 {
        feed.window(&mut online);
    }
    let mut group = c.benchmark_group("deployed");
    group.throughput(Throughput::Elements(1));
    group.bench_function("per_window", |b| b.iter(|| feed.window(&mut online)));
    group.finish();

    let mut times = Vec::with_capacity(TAIL_WINDOWS);
    for _ in 0..TAIL_WINDOWS {
        let t = Instant::now();
        feed.window(&mut online);
        times.push(t.elapsed().as_nanos() as f64 / 1000.0);
    }
    times.sort_by(f64::total_cmp);
    let q = |p: f64| times[((p * (times.len() - 1) as f64).round()) as usize];
    println!(
        "deployed/per_window one by one ({} windows, {}): median {:.2} µs, p99 {:.2} µs, p99.9 {:.2} µs",
        TAIL_WINDOWS,
        path.display(),
        q(0.5),
        q(0.99),
        q(0.999)
    );

    let pipeline = model.pipeline().expect("the model's pipeline");
    let ctx = pipeline
        .build_windows(&recs, Experiment::Recognition)
        .expect("context windows");
    let win = pipeline
        .without_context()
        .build_windows(&recs, Experiment::Recognition)
        .expect("window rows");
    let k = model.experiment().n_classes();
    let mut out_ctx = vec![0f32; ctx.n_rows() * k];
    let mut out_win = vec![0f32; win.n_rows() * k];
    let mut group = c.benchmark_group("deployed");
    group.throughput(Throughput::Elements(ctx.n_rows() as u64));
    group.sample_size(10);
    group.bench_function("batch", |b| {
        b.iter(|| {
            model
                .context_forest
                .predict_proba_batch(&ctx.x, ctx.n_features, &mut out_ctx)
                .expect("batch");
            model
                .window_forest
                .predict_proba_batch(&win.x, win.n_features, &mut out_win)
                .expect("batch");
            black_box((&out_ctx, &out_win));
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
