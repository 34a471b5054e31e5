//! What the mission log costs per second of the sensor's stream (400 samples), on one core:
//!
//! * `mcap/json_only_400`: the baseline, the 400 samples' JSON values built and encoded (what a
//!   front end's progress callback sees anyway), nothing written;
//! * `mcap/log_400`: the same samples logged to an open `mission.mcap` (JSON on `/tactile`, the
//!   Foxglove SDK's MCAP sink, zstd chunks), plus the arm's 100 states as transforms;
//! * `mcap/open_and_close`: creating a log (13 channels) and writing its summary;
//! * `mcap/log_file_400`: a whole log of that second: created, the samples and transforms logged,
//!   closed (the baseline of the next);
//! * `mcap/ros2_bag_400`: the same second, as `crackbot log to-ros2` handles it once read back:
//!   converted to ROS 2 messages (CDR) and written as a bag folder (MCAP storage and
//!   `metadata.yaml`).
//!
//! The ratio log / baseline is what logging adds; bag / log file what the ROS 2 bag costs beside
//! the log. `taskset -c 1 cargo bench --bench mcap`.

use std::hint::black_box;

use crackbot_mcap::{JsonTopic, LogWriter, LoggedMessage, MissionLog, Payload};
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
    g.bench_function("log_file_400", |b| {
        let path = dir.path().join("second.mcap");
        b.iter(|| {
            let log = LogWriter::create(&path, 0).expect("the log");
            for (i, &(t, raw)) in samples.iter().enumerate() {
                log.json(JsonTopic::Tactile, t, &value(t, raw))
                    .expect("logged");
                if i % 4 == 0 {
                    log.finger_at(t, [t * 4.6, 10.0, 0.0]);
                }
            }
            black_box(log.finish().expect("closed"));
        });
    });
    let read_back = MissionLog {
        path: dir.path().join("second.mcap"),
        messages: logged_second(&samples),
    };
    g.bench_function("ros2_bag_400", |b| {
        let mut k = 0u64;
        b.iter(|| {
            k += 1;
            let bag = dir.path().join(format!("bag{k}"));
            let messages = crackbot_rosbag::convert(&read_back).expect("converted");
            black_box(crackbot_rosbag::write_bag(&bag, &messages).expect("written"));
            std::fs::remove_dir_all(&bag).expect("removed");
        });
    });
    g.finish();
    log.finish().expect("closed");
}

/// The second as the log reads back: the samples on `/tactile`, the arm's poses on `/arm/pose`.
fn logged_second(samples: &[(f64, [u16; 4])]) -> Vec<LoggedMessage> {
    let mut out = Vec::new();
    for (i, &(t, raw)) in samples.iter().enumerate() {
        let ns = (t * 1e9) as u64;
        out.push(LoggedMessage {
            topic: JsonTopic::Tactile.topic().into(),
            log_time_ns: ns,
            payload: Payload::Json(value(t, raw)),
        });
        if i % 4 == 0 {
            let pose = serde_json::json!({"t_s": t, "x_mm": t * 4.6, "y_mm": 10.0, "z_mm": 0.0});
            out.push(LoggedMessage {
                topic: JsonTopic::ArmPose.topic().into(),
                log_time_ns: ns,
                payload: Payload::Json(pose),
            });
        }
    }
    out
}

criterion_group!(benches, bench);
criterion_main!(benches);
