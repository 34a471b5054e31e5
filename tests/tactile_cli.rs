//! `crackbot tactile convert` end to end: the authors' MAT-files to CSV and back, and its errors.

use std::path::{Path, PathBuf};

use crackbot_recording::{read_csv, read_mat};
use crackbot_testkit::assert_bits_equal;
use crackbot_tests::{crackbot, text};

/// A file or folder of the authors' recordings (`../shared/data/tactile/...`); stops the test with one
/// clear message when the shared data is missing.
fn data(rel: &str) -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE).join(rel)
}

fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn convert_mat_files_to_csv_bit_for_bit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("csv");
    let inputs = [
        data("type/crack_crack_complete_1.mat"),
        data("width/crack_mm8_complete_3.mat"),
    ];
    let result = crackbot(&[
        "tactile",
        "convert",
        utf8(&inputs[0]),
        utf8(&inputs[1]),
        "--out",
        utf8(&out),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let stdout = text(&result.stdout);
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    assert!(
        stdout.contains("crack_crack_complete_1.csv: 33944 rows, 13 slides, label 1, repetition 1"),
        "{stdout}"
    );
    assert!(
        stdout.contains("crack_mm8_complete_3.csv: 33428 rows, 13 slides, label 8, repetition 3"),
        "{stdout}"
    );
    for input in &inputs {
        let stem = input.file_stem().expect("stem");
        let csv = out.join(stem).with_extension("csv");
        let original = read_mat(input).expect("read .mat");
        let converted = read_csv(&csv).expect("read .csv");
        assert_bits_equal(&converted, &original, &csv.display().to_string());
    }

    // One input and a .csv --out: that file. CSV → CSV normalises; CSV → MAT reads back the same.
    let single = dir.path().join("one/single.csv");
    let result = crackbot(&[
        "tactile",
        "convert",
        utf8(&out.join("crack_mm8_complete_3.csv")),
        "--out",
        utf8(&single),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let original = read_mat(&inputs[1]).expect("read .mat");
    assert_bits_equal(&read_csv(&single).expect("read"), &original, "csv → csv");
    let mat = dir.path().join("back.mat");
    let result = crackbot(&["tactile", "convert", utf8(&single), "--out", utf8(&mat)]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    assert_bits_equal(&read_mat(&mat).expect("read"), &original, "csv → mat");
}

#[test]
fn convert_a_folder() {
    let dir = tempfile::tempdir().expect("temp dir");
    let result = crackbot(&[
        "tactile",
        "convert",
        utf8(&data("type")),
        "--out",
        utf8(dir.path()),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    assert_eq!(text(&result.stdout).lines().count(), 12);
    let csv = dir.path().join("crack_pattern_complete_2.csv");
    assert_eq!(read_csv(&csv).expect("read").label(), Some(3.0));
}

#[test]
fn bad_inputs_are_named_errors_not_panics() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("broken.mat");
    let bytes = std::fs::read(data("type/crack_bump_complete_2.mat")).expect("read");
    std::fs::write(&bad, &bytes[..bytes.len() / 3]).expect("write");
    let good = data("type/crack_bump_complete_1.mat");
    let out = dir.path().join("out");
    let result = crackbot(&[
        "tactile",
        "convert",
        utf8(&good),
        utf8(&bad),
        "--out",
        utf8(&out),
    ]);
    assert!(!result.status.success());
    let err = text(&result.stderr);
    assert!(
        err.contains(utf8(&bad)) && err.contains("truncated"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // Nothing was written: every input is read before any output.
    assert!(!out.join("crack_bump_complete_1.csv").exists());

    // An output with an unknown extension is neither a file nor a folder.
    let txt = dir.path().join("out.txt");
    let result = crackbot(&["tactile", "convert", utf8(&good), "--out", utf8(&txt)]);
    assert!(!result.status.success());
    let err = text(&result.stderr);
    assert!(
        err.contains(utf8(&txt)) && err.contains(".csv or .mat"),
        "{err}"
    );
    assert!(!txt.exists());

    let cases: [(&[&str], &str); 3] = [
        (&["nope.mat"], "no such file"),
        (&["notes.txt"], "unsupported extension"),
        (&["a.csv", "b.csv"], "names one file"),
    ];
    std::fs::write(dir.path().join("notes.txt"), "hello").expect("write");
    for name in ["a.csv", "b.csv"] {
        let csv = dir.path().join(name);
        let r = crackbot(&["tactile", "convert", utf8(&good), "--out", utf8(&csv)]);
        assert!(r.status.success(), "{}", text(&r.stderr));
    }
    for (inputs, fact) in cases {
        let mut args = vec!["tactile", "convert"];
        let paths: Vec<String> = inputs
            .iter()
            .map(|n| dir.path().join(n).display().to_string())
            .collect();
        args.extend(paths.iter().map(String::as_str));
        let target = dir.path().join("x.csv");
        args.extend(["--out", utf8(&target)]);
        let result = crackbot(&args);
        assert!(!result.status.success(), "{inputs:?}");
        let err = text(&result.stderr);
        assert!(
            err.contains(&paths[0]) || err.contains(utf8(&target)),
            "{err}"
        );
        assert!(err.contains(fact), "{inputs:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

fn tactile_data(experiment: &str, repetition: u32) -> Vec<String> {
    let mut files: Vec<String> = std::fs::read_dir(data(experiment))
        .expect("the authors' recordings beside the clone")
        .map(|e| e.expect("dir entry").path().display().to_string())
        .filter(|p| p.ends_with(&format!("_{repetition}.mat")))
        .collect();
    files.sort();
    files
}

fn eval_json(train: &[String], test: &[String], extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<&str> = vec!["tactile", "eval", "--json", "--trees", "30", "--train"];
    args.extend(train.iter().map(String::as_str));
    args.push("--test");
    args.extend(test.iter().map(String::as_str));
    args.extend_from_slice(extra);
    let out = std::process::Command::new(crackbot_tests::binary("crackbot"))
        .args(&args)
        .output()
        .expect("running crackbot");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

#[test]
fn eval_recognition_trained_on_one_repetition_tested_on_another() {
    let train = tactile_data("type", 1);
    let test = tactile_data("type", 2);
    assert_eq!((train.len(), test.len()), (4, 4));
    let r = eval_json(&train, &test, &[]);
    assert_eq!(r["experiment"], "recognition");
    let window = r["window_accuracy"].as_f64().expect("window_accuracy");
    let slide = r["slide_accuracy"].as_f64().expect("slide_accuracy");
    // Intersession, MAV D1D2+P, 30 trees: ~84% of windows and every slide right (measured);
    // the bounds leave room for seed noise but fail on a broken pipeline (chance is 25%).
    assert!(window > 0.75, "window accuracy {window}");
    assert!(slide >= 0.9, "slide accuracy {slide}");
    assert_eq!(r["test_slides"], 48);
    assert!(r["width_mae_mm"].is_null());
    assert!(r["slide_width_reported_mae_mm"].is_null());
    let confusion = r["window_confusion"].as_array().expect("confusion");
    let total: u64 = confusion
        .iter()
        .flat_map(|row| row.as_array().expect("row").iter())
        .map(|v| v.as_u64().expect("count"))
        .sum();
    assert_eq!(total, r["test_windows"].as_u64().expect("test_windows"));
}

#[test]
fn eval_with_context_beats_the_paper_windows_and_keeps_every_slide() {
    let train = tactile_data("type", 1);
    let test = tactile_data("type", 2);
    let plain = eval_json(&train, &test, &[]);
    let ctx = eval_json(&train, &test, &["--context"]);
    let alone = eval_json(&train, &test, &["--context", "--slide-vote", "context"]);
    assert_eq!(ctx["slide_vote"], "context+paper");
    assert_eq!(alone["slide_vote"], "context");
    assert_eq!(plain["slide_vote"], "paper");
    let acc = |r: &serde_json::Value, k: &str| r[k].as_f64().expect(k);
    // Measured with 30 trees: paper windows ~84%, context windows ~97%, every slide right.
    assert!(
        acc(&ctx, "window_accuracy") > acc(&plain, "window_accuracy") + 0.05,
        "context {} vs paper {}",
        acc(&ctx, "window_accuracy"),
        acc(&plain, "window_accuracy")
    );
    assert!(acc(&ctx, "window_accuracy") > 0.9);
    assert!(acc(&ctx, "slide_accuracy") >= 0.99);
    // The vote changes slides only: the windows are the context forest's in both runs.
    assert_eq!(ctx["window_confusion"], alone["window_confusion"]);
    assert_eq!(ctx["test_slides"], 48);
}

#[test]
fn eval_width_reports_regression_error() {
    let train = tactile_data("width", 1);
    let test = tactile_data("width", 3);
    let r = eval_json(&train, &test, &["--classifier", "qda"]);
    assert_eq!(r["experiment"], "width");
    assert_eq!(r["classifier"], "QDA");
    let mae = r["width_mae_mm"].as_f64().expect("width_mae_mm");
    let slide_mae = r["slide_width_mae_mm"]
        .as_f64()
        .expect("slide_width_mae_mm");
    // Predicting the mean width (4.33 mm) would give an MAE of ~3.4 mm.
    assert!(
        mae < 3.0 && slide_mae < 2.5,
        "MAE {mae} mm per window, {slide_mae} mm per slide"
    );
    assert!(r["window_accuracy"].as_f64().expect("acc") > 1.0 / 6.0);
    // The width the robot reports is the slide verdict's class width: its error follows from
    // the slide confusion (rows = true widths 0, 1, 2, 5, 8, 10 mm).
    let widths = [0.0, 1.0, 2.0, 5.0, 8.0, 10.0];
    let (mut error, mut slides) = (0.0, 0.0);
    for (row, truth) in r["slide_confusion"]
        .as_array()
        .expect("slides")
        .iter()
        .zip(widths)
    {
        for (count, said) in row.as_array().expect("row").iter().zip(widths) {
            let count = count.as_f64().expect("count");
            error += count * f64::abs(said - truth);
            slides += count;
        }
    }
    let reported = r["slide_width_reported_mae_mm"]
        .as_f64()
        .expect("slide_width_reported_mae_mm");
    assert!(
        (reported - error / slides).abs() < 1e-9,
        "{reported} vs {}",
        error / slides
    );
}

#[test]
fn eval_rejects_mixed_experiments_and_missing_paths() {
    let mut train = tactile_data("type", 1);
    train.extend(tactile_data("width", 1));
    let out = std::process::Command::new(crackbot_tests::binary("crackbot"))
        .args(["tactile", "eval", "--train"])
        .args(&train)
        .args(["--test", "/nonexistent/recordings"])
        .output()
        .expect("running crackbot");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/recordings"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let test = tactile_data("width", 2);
    let out = std::process::Command::new(crackbot_tests::binary("crackbot"))
        .args(["tactile", "eval", "--train"])
        .args(&train)
        .arg("--test")
        .args(&test)
        .output()
        .expect("running crackbot");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("neither"), "{err}");
}

/// `crackbot tactile …` runs the research binary under the name the user typed, so its help
/// and its errors say `crackbot tactile`, not the binary behind it.
#[test]
fn forwarded_commands_speak_under_the_name_the_user_typed() {
    let o = crackbot(&["tactile", "eval", "--help"]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{out}{}", text(&o.stderr));
    assert!(out.contains("Usage: crackbot tactile eval"), "{out}");
    let o = crackbot(&["sim", "dataset", "--no-such-flag"]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("crackbot sim dataset"), "{err}");
    assert!(!err.contains("crackbot-lab"), "{err}");
}

#[test]
fn convert_reads_width_recordings_as_surface_types_and_names_a_bad_width() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("as-type");
    let inputs = [
        data("width/crack_mm0_complete_3.mat"),
        data("width/crack_mm8_complete_3.mat"),
    ];
    let result = crackbot(&[
        "tactile",
        "convert",
        "--width-as-recognition",
        utf8(&inputs[0]),
        utf8(&inputs[1]),
        "--out",
        utf8(&out),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let label = |name: &str| read_csv(&out.join(name)).expect("read").label();
    assert_eq!(label("crack_mm0_complete_3.csv"), Some(0.0));
    assert_eq!(label("crack_mm8_complete_3.csv"), Some(1.0));
    // A surface-type recording of the wavy plate (label 3) is no width: named, nothing written.
    let wavy = data("type/crack_pattern_complete_1.mat");
    let target = dir.path().join("wavy.csv");
    let result = crackbot(&[
        "tactile",
        "convert",
        "--width-as-recognition",
        utf8(&wavy),
        "--out",
        utf8(&target),
    ]);
    assert!(!result.status.success());
    let err = text(&result.stderr);
    assert!(
        err.contains("crack_pattern_complete_1.mat") && err.contains("3 is no width"),
        "{err}"
    );
    assert!(!target.exists());
}

/// `tactile eval --model MODEL --test TEST --json`: the shares of slides and of windows right,
/// 0–1.
fn model_accuracy(model: &Path, test: &Path) -> (f64, f64) {
    let r = crackbot(&[
        "tactile",
        "eval",
        "--json",
        "--model",
        utf8(model),
        "--test",
        utf8(test),
    ]);
    assert!(r.status.success(), "{}", text(&r.stderr));
    let json: serde_json::Value = serde_json::from_slice(&r.stdout).expect("JSON");
    let share = |key: &str| {
        json[key]
            .as_f64()
            .unwrap_or_else(|| panic!("{key} in {json}"))
    };
    (share("slide_accuracy"), share("window_accuracy"))
}

/// `tactile train` with `--trees 8 --max-depth 8` into `out` (each kind of recordings given
/// where there are some), `extra` appended; its stderr.
fn train_small(recognition: &[String], width: &[String], out: &Path, extra: &[&str]) -> String {
    let mut args: Vec<&str> = vec!["tactile", "train", "--trees", "8", "--max-depth", "8"];
    for (flag, files) in [("--recognition", recognition), ("--width", width)] {
        if !files.is_empty() {
            args.push(flag);
            args.extend(files.iter().map(String::as_str));
        }
    }
    args.extend(["--out", utf8(out)]);
    args.extend_from_slice(extra);
    let r = crackbot(&args);
    assert!(r.status.success(), "{}", text(&r.stderr));
    text(&r.stderr)
}

#[test]
fn the_recognition_model_learns_every_crack_width_unless_told_not_to() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (pooled, type_only) = (dir.path().join("pooled"), dir.path().join("type-only"));
    // The flat, 1 mm and 10 mm width plates (fewer files keep the test short).
    let types = tactile_data("type", 1);
    let widths: Vec<String> = tactile_data("width", 1)
        .into_iter()
        .filter(|p| ["mm0_", "mm1_", "mm10_"].iter().any(|w| p.contains(w)))
        .collect();
    assert_eq!(widths.len(), 3);
    let said = train_small(&types, &widths, &pooled, &[]);
    assert!(
        said.contains("7 recordings (3 of them width plates"),
        "{said}"
    );
    let said = train_small(&types, &widths, &type_only, &["--recognition-type-only"]);
    assert!(
        said.contains("recognition: 4 recordings,") && !said.contains("width plates read"),
        "{said}"
    );
    let listed = |d: &Path| -> Vec<String> {
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(d.join("recognition.json")).expect("summary"),
        )
        .expect("JSON");
        json["training"]["recordings"]
            .as_array()
            .expect("recordings")
            .iter()
            .map(|r| r.as_str().expect("name").to_string())
            .collect()
    };
    assert_eq!(listed(&pooled).len(), 4 + 3);
    assert!(listed(&pooled)
        .iter()
        .any(|r| r.contains("crack_mm10_complete_1")));
    assert_eq!(listed(&type_only).len(), 4);
    // The thinnest and the widest crack of another session, read as surface types.
    let test = dir.path().join("test");
    let result = crackbot(&[
        "tactile",
        "convert",
        "--width-as-recognition",
        utf8(&data("width/crack_mm1_complete_2.mat")),
        utf8(&data("width/crack_mm10_complete_2.mat")),
        "--out",
        utf8(&test),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let slides = |model: &Path| model_accuracy(&model.join("recognition.ctm"), &test).0;
    // Measured with 32 trees on repetitions 1–2 of every plate: the type-only model calls all
    // 24 of these slides "bump", the pooled one calls every one a crack.
    let (with, without) = (slides(&pooled), slides(&type_only));
    assert!(
        with >= 0.9,
        "pooled model: {with} of the 1 and 10 mm slides are cracks"
    );
    assert!(without <= 0.5, "type-only model: {without}");
}

/// The training recordings that the summary of the model `kind` in `out` lists (`kind`:
/// `recognition` or `width`).
fn trained_on(out: &Path, kind: &str) -> Vec<String> {
    let summary = std::fs::read_to_string(out.join(format!("{kind}.json"))).expect("summary");
    let summary: serde_json::Value = serde_json::from_str(&summary).expect("JSON");
    summary["training"]["recordings"]
        .as_array()
        .expect("recordings")
        .iter()
        .map(|r| r.as_str().expect("name").to_string())
        .collect()
}

/// `crackbot sim dataset --experiment <experiment> --seed <seed> --out <out>`.
fn sim_dataset(experiment: &str, seed: &str, out: &Path) {
    let r = crackbot(&[
        "sim",
        "dataset",
        "--experiment",
        experiment,
        "--seed",
        seed,
        "--out",
        utf8(out),
    ]);
    assert!(r.status.success(), "{}", text(&r.stderr));
}

#[test]
fn the_width_model_learns_the_simulated_plates_when_asked() {
    let dir = tempfile::tempdir().expect("temp dir");
    let widths = tactile_data("width", 1);
    assert_eq!(widths.len(), 6);
    let (real, joint) = (dir.path().join("real"), dir.path().join("joint"));
    train_small(&[], &widths, &real, &[]);
    train_small(&[], &widths, &joint, &["--width-sim-seeds", "8"]);
    let names = trained_on(&joint, "width");
    // Six real recordings and the simulator's thirty (six plates, five recordings each), named
    // by their seed.
    assert_eq!(names.len(), 6 + 30, "{names:?}");
    assert!(
        names.iter().any(|n| n == "sim-seed8-crack_mm2_complete_5"),
        "{names:?}"
    );
    // Simulated plates of a seed neither model trained on.
    let sim = dir.path().join("sim12");
    sim_dataset("width", "12", &sim);
    let slides = |model: &Path| model_accuracy(&model.join("width.ctm"), &sim).0;
    let (real, joint) = (slides(&real), slides(&joint));
    assert!(
        joint >= 0.9 && joint > real + 0.15,
        "real only {real}, with seed 8 {joint}"
    );
    // Simulated plates are added to the width model only.
    let r = crackbot(&[
        "tactile",
        "train",
        "--recognition",
        utf8(&data("type")),
        "--width-sim-seeds",
        "8",
        "--out",
        utf8(dir.path()),
    ]);
    assert!(!r.status.success());
    assert!(
        text(&r.stderr).contains("--width-sim-seeds adds simulated plates to the width model"),
        "{}",
        text(&r.stderr)
    );
}

/// Issue 12's sim → real goal: a forest trained on simulated plates alone reads ≥ 80 % of the
/// real windows and every real slide of the repetitions the simulator was not fitted on (2 and
/// 3). Seed 28, 30 trees: 95.4 % of windows since the simulated fibre's floor is darker (dark
/// level 215 counts, chosen on repetition 1); 67.5 % with the fitted 284.73 (100 trees;
/// `crates/sim/docs/calibration.md`, "A darker proximity floor, adopted").
#[test]
fn a_forest_trained_on_the_simulator_reads_the_real_finger() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sim = dir.path().join("sim28");
    sim_dataset("recognition", "28", &sim);
    let mut test = tactile_data("type", 2);
    test.extend(tactile_data("type", 3));
    assert_eq!(test.len(), 8);
    let r = eval_json(&[utf8(&sim).to_string()], &test, &["--context"]);
    let window = r["window_accuracy"].as_f64().expect("window_accuracy");
    let slide = r["slide_accuracy"].as_f64().expect("slide_accuracy");
    assert_eq!(r["test_slides"], 96);
    assert!(window >= 0.8, "sim → real: {window} of the real windows");
    assert!(slide >= 1.0, "sim → real: {slide} of the real slides");
}

#[test]
fn the_recognition_model_learns_the_simulated_plates_when_asked() {
    let dir = tempfile::tempdir().expect("temp dir");
    let types = tactile_data("type", 1);
    assert_eq!(types.len(), 4);
    let (real, joint) = (dir.path().join("real"), dir.path().join("joint"));
    train_small(&types, &[], &real, &[]);
    train_small(&types, &[], &joint, &["--recognition-sim-seeds", "8"]);
    let names = trained_on(&joint, "recognition");
    // Four real recordings and the simulator's twenty (four plates, five recordings each).
    assert_eq!(names.len(), 4 + 20, "{names:?}");
    assert!(
        names
            .iter()
            .any(|n| n == "sim-seed8-crack_pattern_complete_5"),
        "{names:?}"
    );
    // Simulated plates of a seed neither model trained on. With strokes starting 5–10 mm before
    // the feature the real repetition alone read 87.9 % of their slides, seed 8's plates 100 %;
    // since they start 6–7.4 mm before it, as the real ones do, both read nearly every slide
    // and the windows tell them apart: measured 60.9 % of windows (98.3 % of slides) from the real
    // repetition alone, 93.4 % (100 %) with seed 8's plates; since the simulated fibre's floor is
    // darker (dark level 215 counts) 60.6 % (93.3 %) and 96.3 % (100 %).
    let sim = dir.path().join("sim23");
    sim_dataset("recognition", "23", &sim);
    let shares = |model: &Path| model_accuracy(&model.join("recognition.ctm"), &sim);
    let ((_, real_windows), (joint_slides, joint_windows)) = (shares(&real), shares(&joint));
    assert!(
        joint_slides >= 0.95 && joint_windows > real_windows + 0.1,
        "windows: real only {real_windows}, with seed 8 {joint_windows} (slides {joint_slides})"
    );
    // Simulated plates need real ones to join.
    let r = crackbot(&[
        "tactile",
        "train",
        "--width",
        utf8(&data("width")),
        "--recognition-sim-seeds",
        "8",
        "--out",
        utf8(dir.path()),
    ]);
    assert!(!r.status.success());
    assert!(
        text(&r.stderr)
            .contains("--recognition-sim-seeds adds simulated plates to the recognition model"),
        "{}",
        text(&r.stderr)
    );
}
