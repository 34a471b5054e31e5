//! What the mission log costs per second of the sensor's stream (400 samples), on one core:
//!
//! * `mcap/json_only_400`: the baseline, the 400 samples' JSON values built and encoded (what a
//!   front end's progress callback sees anyway), nothing written;
//! * `mcap/log_400`: the same samples logged to an open `mission.mcap` (JSON on `/tactile`, the
//!   Foxglove SDK's MCAP sink, zstd chunks), plus the arm's 100 states as transforms;
//! * `mcap/open_and_close`: creating a log (13 channels) and writing its summary.
//!
//! The ratio log / baseline is what logging adds; `taskset -c 1 cargo bench --bench mcap`.

use std::hint::black_box;

use crackbot_mcap::{JsonTopic, LogWriter};
use criterion::{criterion_group, criterion_main, Criterion};

/// One second of samples: (t_s, D1, D2, D3, P).
fn second() -> Vec<(f64, [u16; 4])> {
    (0..400u16)
        .map(|i| {
            let t = f64::from(i) / 400.0;
            (t, [650 + i % 7, 420 + i % 5, 700 + i % 3, 200 + i % 300])
        })
        .collect()
}

fn value(t: f64, raw: [u16; 4]) -> serde_json::Value {
    serde_json::json!({
        "t_s": t, "d1": raw[0], "d2": raw[1], "d3": raw[2], "p": raw[3],
        "slide": 3, "along_mm": t * 4.6,
    })
}

fn bench(c: &mut Criterion) {
    let samples = second();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut g = c.benchmark_group("mcap");
    g.bench_function("json_only_400", |b| {
        b.iter(|| {
            for &(t, raw) in &samples {
                black_box(serde_json::to_vec(&value(t, raw)).expect("json"));
            }
        });
    });
    let log = LogWriter::create(&dir.path().join("bench.mcap"), 0).expect("the log");
    g.bench_function("log_400", |b| {
        b.iter(|| {
            for (i, &(t, raw)) in samples.iter().enumerate() {
                log.json(JsonTopic::Tactile, t, &value(t, raw))
                    .expect("logged");
                if i % 4 == 0 {
                    log.finger_at(t, [t * 4.6, 10.0, 0.0]);
                }
            }
        });
    });
    g.bench_function("open_and_close", |b| {
        let path = dir.path().join("small.mcap");
        b.iter(|| {
            let log = LogWriter::create(&path, 0).expect("the log");
            log.json(JsonTopic::Status, 0.0, &serde_json::json!({"stage": "x"}))
                .expect("logged");
            black_box(log.finish().expect("closed"));
        });
    });
    g.finish();
    log.finish().expect("closed");
}

criterion_group!(benches, bench);
criterion_main!(benches);
