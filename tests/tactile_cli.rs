//! `crackbot tactile convert` end to end: the authors' MAT-files to CSV and back, and its errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use crackbot_recording::{read_csv, read_mat, Recording, Row};
use crackbot_tests::binary;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/tactile");

fn data(rel: &str) -> PathBuf {
    Path::new(DATA).join(rel)
}

fn crackbot(args: &[&str]) -> Output {
    Command::new(binary("crackbot"))
        .args(args)
        .output()
        .expect("running crackbot")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn utf8(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn bits(r: &Row) -> [u64; 9] {
    [
        r.x_mm.to_bits(),
        r.d1.to_bits(),
        r.d2.to_bits(),
        r.d3.to_bits(),
        r.p.to_bits(),
        u64::from(r.direction),
        u64::from(r.slide),
        r.label.to_bits(),
        u64::from(r.repetition),
    ]
}

fn assert_bits_equal(a: &Recording, b: &Recording, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    assert_eq!(a.extra, b.extra, "{what}");
    for (i, (x, y)) in a.rows.iter().zip(&b.rows).enumerate() {
        assert_eq!(bits(x), bits(y), "{what}: row {i}");
    }
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
