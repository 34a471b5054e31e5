//! Our forest files exported to ONNX (`scripts/forest_to_onnx.sh`) give ONNX Runtime's
//! `TreeEnsembleClassifier` / `TreeEnsembleRegressor` our outputs: the same class probabilities (to
//! 1e-6) and the same class on every real window of repetition 2, the same regression values, NaN
//! features going right; corrupted files are refused by the exporter.
//!
//! Needs what `bash scripts/setup.sh` installs: ONNX Runtime 1.31.1 (as the vision ONNX tests) and the
//! exporter's venv (made by `scripts/forest_to_onnx.sh` on first use). Without them the tests fail,
//! naming the fix. The runtime is loaded once per process: every ONNX check is in one test.

#[path = "../benches/common/onnx_forest.rs"]
mod onnx_forest;
#[path = "../benches/common/windows.rs"]
mod windows;

use std::path::Path;

use crackbot_forest::{Classifier, ForestParams, RandomForest, RandomForestRegressor};
use onnx_forest::{compare, export, OrtForest, Ours};

fn or_fail<T>(r: Result<T, String>) -> T {
    r.unwrap_or_else(|e| panic!("{e}"))
}

fn export_and_load(forest: &Path, dir: &Path, name: &str) -> (Ours, OrtForest) {
    let onnx = dir.join(format!("{name}.onnx"));
    or_fail(export(forest, &onnx));
    let ours = or_fail(Ours::load(forest));
    let ort = or_fail(OrtForest::load(&onnx, ours.n_features(), 1));
    (ours, ort)
}

#[test]
fn onnx_runtime_predicts_like_our_forests() {
    let real = windows::load(&windows::data_dir());
    let nf = real.train.n_features;
    let dir = tempfile::tempdir().expect("temp dir");

    // Classifiers: the bench's 100 fully grown trees (probabilities 0/1 mostly; exact vote ties occur),
    // depth-capped trees (mixed leaves), and two classes (ONNX Runtime's binary conventions), with class
    // labels that are not 0..K (kept in the ONNX metadata; ONNX's `label` is the class index).
    let n_classes = real.train.experiment.n_classes();
    let four = crackbot_forest::Dataset::with_classes(
        real.train.x.clone(),
        nf,
        real.train.y.clone(),
        n_classes,
    )
    .expect("training set");
    let two = crackbot_forest::Dataset::with_classes(
        real.train.x.clone(),
        nf,
        real.train.y.iter().map(|&c| u32::from(c != 0)).collect(),
        2,
    )
    .expect("two-class training set");
    for (name, train, trees, depth) in [
        ("grown", &four, 100, None),
        ("depth6", &four, 15, Some(6)),
        ("binary", &two, 15, Some(10)),
    ] {
        let forest = RandomForest::fit(
            train,
            &ForestParams::classifier()
                .n_trees(trees)
                .max_depth(depth)
                .seed(1)
                .quiet(true),
        )
        .expect("forest")
        .with_class_labels(
            (0..train.n_classes())
                .map(|c| 0.5 + c as f64 * 0.25)
                .collect(),
        )
        .expect("labels");
        let path = dir.path().join(format!("{name}.forest"));
        forest.save(&path).expect("save");
        let (ours, mut ort) = export_and_load(&path, dir.path(), name);
        let a = or_fail(compare(&ours, &mut ort, &real.test.x));
        println!(
            "{name}: {} windows, max |Δp| {:.2e}, class differs on {}",
            a.rows,
            a.max_diff,
            a.class_differs.len()
        );
        assert_eq!(a.rows, real.test.n_rows());
        assert!(a.max_diff <= 1e-6, "{name}: max |Δp| = {}", a.max_diff);
        assert!(
            a.class_differs.is_empty(),
            "{name}: ONNX Runtime's class differs from ours on windows {:?}",
            &a.class_differs[..a.class_differs.len().min(20)]
        );
        // One row at a time, as the robot runs it.
        for r in (0..real.test.n_rows()).step_by(997) {
            let row = real.test.row(r);
            assert_eq!(ort.run_one(row), forest.predict(row) as f32, "window {r}");
        }
        // NaN features go right in both (a missing sensor value).
        let mut x = real.test.x[..600 * nf].to_vec();
        for (i, v) in x.iter_mut().enumerate() {
            if i % 7 == 0 || i % 11 == 3 {
                *v = f32::NAN;
            }
        }
        let a = or_fail(compare(&ours, &mut ort, &x));
        assert!(
            a.max_diff <= 1e-6 && a.class_differs.is_empty(),
            "{name} with NaN: max |Δp| {}, {} classes differ",
            a.max_diff,
            a.class_differs.len()
        );
    }

    // Regressor: a window's P feature from its D1 and D2 MAV (any continuous target will do).
    let x: Vec<f32> = real.train.x.chunks(nf).flat_map(|r| [r[0], r[1]]).collect();
    let y: Vec<f32> = real.train.x.chunks(nf).map(|r| r[2]).collect();
    let data = crackbot_forest::RegressionDataset::new(x, 2, y).expect("regression set");
    let reg = RandomForestRegressor::fit(
        &data,
        &ForestParams::regressor()
            .n_trees(10)
            .max_depth(Some(12))
            .seed(5)
            .quiet(true),
    )
    .expect("regressor");
    let path = dir.path().join("reg.forest");
    reg.save(&path).expect("save");
    let (ours, mut ort) = export_and_load(&path, dir.path(), "reg");
    let x: Vec<f32> = real.test.x.chunks(nf).flat_map(|r| [r[0], r[1]]).collect();
    let a = or_fail(compare(&ours, &mut ort, &x));
    println!(
        "regressor: {} windows, max relative |Δ| {:.2e}",
        a.rows, a.max_diff
    );
    assert!(
        a.max_diff <= 1e-6,
        "regressor: max relative |Δ| {}",
        a.max_diff
    );
    assert_eq!(ort.run_one(&x[..2]), reg.predict(&x[..2]));
}

#[test]
fn the_exporter_refuses_corrupted_forest_files() {
    let data = crackbot_forest::synthetic::blobs(400, 3, 3, 30.0, 1).expect("data");
    let forest = RandomForest::fit(
        &data,
        &ForestParams::classifier().n_trees(3).seed(1).quiet(true),
    )
    .expect("forest");
    let good = forest.to_bytes();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut flipped = good.clone();
    flipped[60] ^= 0x10;
    let mut version = good.clone();
    version[8] = 9;
    let cases: [(&str, Vec<u8>, &str); 5] = [
        ("flipped", flipped, "checksum mismatch"),
        ("truncated", good[..good.len() - 9].to_vec(), "truncated"),
        (
            "trailing",
            [&good[..], &[0u8; 3]].concat(),
            "trailing bytes",
        ),
        ("version", version, "format version 9"),
        ("magic", b"NOTAFOREST and more bytes".to_vec(), "bad magic"),
    ];
    for (name, bytes, want) in cases {
        let path = dir.path().join(format!("{name}.forest"));
        std::fs::write(&path, &bytes).expect("write");
        let onnx = dir.path().join(format!("{name}.onnx"));
        let err = export(&path, &onnx).expect_err(name);
        assert!(err.contains(want), "{name}: {err}");
        assert!(!onnx.exists(), "{name}: an ONNX file was written");
    }
    // The good file exports.
    let path = dir.path().join("good.forest");
    std::fs::write(&path, &good).expect("write");
    export(&path, &dir.path().join("good.onnx")).unwrap_or_else(|e| panic!("{e}"));
}

/// CRC-32 (ISO-HDLC, as zlib), bit by bit: enough for a test file.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[test]
fn the_exporter_takes_a_section_of_a_deployed_tactile_model() {
    let data = crackbot_forest::synthetic::blobs(400, 5, 3, 30.0, 2).expect("data");
    let forest = RandomForest::fit(
        &data,
        &ForestParams::classifier().n_trees(4).seed(2).quiet(true),
    )
    .expect("forest");
    let window = RandomForest::fit(
        &data,
        &ForestParams::classifier().n_trees(2).seed(3).quiet(true),
    )
    .expect("forest");
    let (a, b) = (forest.to_bytes(), window.to_bytes());
    // The CRKTACTL layout of crates/tactile/src/model.rs: magic, version, header length, JSON header
    // listing the sections, the sections, CRC-32 of all before.
    let header = format!(
        r#"{{"format_version":1,"sections":[{{"name":"context_forest","bytes":{}}},{{"name":"window_forest","bytes":{}}}]}}"#,
        a.len(),
        b.len()
    );
    let mut file = b"CRKTACTL".to_vec();
    file.extend_from_slice(&1u32.to_le_bytes());
    file.extend_from_slice(&(header.len() as u32).to_le_bytes());
    file.extend_from_slice(header.as_bytes());
    file.extend_from_slice(&a);
    file.extend_from_slice(&b);
    let crc = crc32(&file);
    file.extend_from_slice(&crc.to_le_bytes());
    let dir = tempfile::tempdir().expect("temp dir");
    let model = dir.path().join("model.ctm");
    std::fs::write(&model, &file).expect("write");
    assert!(onnx_forest::is_tactile_model(&model));
    for (section, bytes) in [("context_forest", &a), ("window_forest", &b)] {
        let onnx = dir.path().join(format!("{section}.onnx"));
        let out = dir.path().join(format!("{section}.forest"));
        or_fail(onnx_forest::export_section(&model, section, &onnx, &out));
        assert_eq!(&std::fs::read(&out).expect("read"), bytes, "{section}");
        assert!(onnx.is_file());
    }
    let err = onnx_forest::export_section(
        &model,
        "width_regressor",
        &dir.path().join("w.onnx"),
        &dir.path().join("w.forest"),
    )
    .expect_err("no such section");
    assert!(err.contains("no section 'width_regressor'"), "{err}");
    let n = file.len();
    file[n - 10] ^= 1;
    std::fs::write(&model, &file).expect("write");
    let err = onnx_forest::export_section(
        &model,
        "context_forest",
        &dir.path().join("c.onnx"),
        &dir.path().join("c.forest"),
    )
    .expect_err("corrupt");
    assert!(err.contains("checksum mismatch"), "{err}");
}
