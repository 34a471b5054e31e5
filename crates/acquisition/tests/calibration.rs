//! Tests of the per-sensor calibration file.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::{Path, PathBuf};

use crackbot_acquisition::calibration::{Calibration, CalibrationError, CHANNELS, MAX_CONDITION};
use proptest::prelude::*;

fn example_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("calibration/example.toml")
}

fn example() -> Calibration {
    Calibration::load(&example_path()).unwrap()
}

/// A valid calibration with cross-talk and distinct gains.
fn sample() -> Calibration {
    Calibration {
        sensor_id: "test-finger".to_string(),
        offsets: [660.0, 440.0, 720.0, 250.0],
        gains: [1.0, 1.04, 0.97, 1.0],
        matrix: [
            [0.012, -0.0015, 0.0008, 0.0],
            [-0.0015, 0.012, 0.0008, 0.0],
            [0.002, 0.002, 0.04, 0.0],
            [0.0, 0.0, 0.0, -0.02],
        ],
        outputs: [
            "lateral left".to_string(),
            "lateral right".to_string(),
            "normal".to_string(),
            "proximity".to_string(),
        ],
        units: ["N", "N", "N", "mm"].map(str::to_string),
        adc_max: 1023,
    }
}

/// The example file's text with one `key = value` line replaced.
fn example_with(key: &str, line: &str) -> String {
    let text = std::fs::read_to_string(example_path()).unwrap();
    let mut out = String::new();
    let mut skipping = false;
    for l in text.lines() {
        if skipping {
            // Skip the rest of a multi-line array.
            if l.trim_start().starts_with(']') {
                skipping = false;
            }
            continue;
        }
        if l.starts_with(&format!("{key} =")) {
            out.push_str(line);
            out.push('\n');
            skipping = l.trim_end().ends_with('[');
            continue;
        }
        out.push_str(l);
        out.push('\n');
    }
    out
}

fn parse_err(text: &str) -> (CalibrationError, String) {
    let err = Calibration::from_toml_str(text, "sensors/finger-7.toml").unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("sensors/finger-7.toml"),
        "message does not name the file: {msg}"
    );
    (err, msg)
}

#[test]
fn example_loads() {
    let cal = example();
    assert_eq!(cal.sensor_id, "finger-example-01");
    assert_eq!(cal.offsets, [660.0, 440.0, 720.0, 250.0]);
    assert_eq!(cal.adc_max, 1023);
    assert_eq!(cal.units, ["N", "N", "N", "mm"].map(str::to_string));
    assert!(cal.condition_number() < 100.0, "{}", cal.condition_number());
    // At rest every output is zero.
    assert_eq!(cal.apply([660, 440, 720, 250]), [0.0; 4]);
    // Pressing on D3 gives a positive normal force.
    assert!(cal.apply([660, 440, 760, 250])[2] > 0.0);
}

#[test]
fn adc_max_defaults_to_1023() {
    let text = example_with("adc_max", "");
    let cal = Calibration::from_toml_str(&text, "no-adc-max.toml").unwrap();
    assert_eq!(cal.adc_max, 1023);
}

#[test]
fn identity_is_valid_and_passes_counts_through() {
    let cal = Calibration::identity("bare");
    cal.validate().unwrap();
    assert_eq!(cal.condition_number(), 1.0);
    assert_eq!(cal.apply([1, 2, 3, 1023]), [1.0, 2.0, 3.0, 1023.0]);
    assert_eq!(CHANNELS, ["D1", "D2", "D3", "P"]);
}

#[test]
fn save_load_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mut odd = sample();
    odd.sensor_id = "finger \"7\" / Ø".to_string();
    odd.outputs[0] = "line one\nline two # not a comment".to_string();
    odd.units[3] = "µm \\ tab\t".to_string();
    odd.matrix[0][0] = 1e-300;
    odd.matrix[1][1] = -0.0;
    odd.matrix[1][0] = 1.0;
    odd.offsets[0] = 0.1 + 0.2;
    for cal in [sample(), example(), Calibration::identity("id-only"), odd] {
        let path = dir.path().join("saved.toml");
        cal.save(&path).unwrap();
        let back = Calibration::load(&path).unwrap();
        assert_eq!(back, cal);
        assert_eq!(back.matrix[1][1].to_bits(), cal.matrix[1][1].to_bits());
    }
}

#[test]
fn save_refuses_invalid_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let mut cal = sample();
    cal.gains[2] = 0.0;
    let err = cal.save(&path).unwrap_err();
    assert!(
        matches!(err, CalibrationError::ZeroGain { channel: "D3", .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("bad.toml"), "{err}");
    assert!(!path.exists());
}

#[test]
fn apply_invert_round_trip() {
    let cal = sample();
    for raw in [
        [660u16, 440, 720, 250],
        [0, 0, 0, 0],
        [1023, 1023, 1023, 1023],
        [633, 472, 767, 787],
    ] {
        let physical = cal.apply(raw);
        let back = cal.invert(physical).unwrap();
        for i in 0..4 {
            assert!(
                (back[i] - f64::from(raw[i])).abs() < 1e-9,
                "{raw:?} -> {physical:?} -> {back:?}"
            );
        }
    }
}

#[test]
fn apply_matches_formula() {
    let cal = sample();
    let raw = [670u16, 430, 740, 300];
    let x: Vec<f64> = (0..4)
        .map(|i| (f64::from(raw[i]) - cal.offsets[i]) * cal.gains[i])
        .collect();
    let y = cal.apply(raw);
    for (r, out) in y.iter().enumerate() {
        let expected: f64 = (0..4).map(|c| cal.matrix[r][c] * x[c]).sum();
        assert!((out - expected).abs() < 1e-12);
    }
}

#[test]
fn invert_rejects_non_finite_input() {
    let err = sample().invert([0.0, f64::NAN, 0.0, 0.0]).unwrap_err();
    assert!(
        matches!(&err, CalibrationError::NonFinite { field, .. } if field == "physical[1]"),
        "{err:?}"
    );
    assert!(err.to_string().contains("test-finger"), "{err}");
}

#[test]
fn singular_matrix_rejected() {
    let mut cal = sample();
    cal.matrix[1] = cal.matrix[0];
    assert!(cal.condition_number() > 1e15);
    let err = cal.validate().unwrap_err();
    assert!(matches!(err, CalibrationError::Singular { .. }), "{err:?}");
    assert!(err.to_string().contains("singular"), "{err}");
    // Same through a file, and invert refuses too.
    let text = example_with("matrix", "matrix = [[1.0, 2.0, 0.0, 0.0], [1.0, 2.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]");
    let (err, msg) = parse_err(&text);
    assert!(matches!(err, CalibrationError::Singular { .. }), "{err:?}");
    assert!(msg.contains("singular"), "{msg}");
    assert!(matches!(
        cal.invert([0.0; 4]).unwrap_err(),
        CalibrationError::Singular { .. }
    ));
}

#[test]
fn zero_matrix_is_singular_with_infinite_condition() {
    let mut cal = sample();
    cal.matrix = [[0.0; 4]; 4];
    assert_eq!(cal.condition_number(), f64::INFINITY);
    let err = cal.validate().unwrap_err();
    match &err {
        CalibrationError::Singular { condition, .. } => assert_eq!(*condition, f64::INFINITY),
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(
        err.to_string().contains("singular (condition number inf)"),
        "{err}"
    );
}

#[test]
fn near_singular_matrix_rejected() {
    let mut cal = Calibration::identity("near");
    cal.matrix[3][3] = 1e-14;
    let condition = cal.condition_number();
    assert!((condition / 1e14 - 1.0).abs() < 1e-6, "{condition}");
    let err = cal.validate().unwrap_err();
    assert!(matches!(err, CalibrationError::Singular { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("ill-conditioned (condition number 1") && msg.contains("e14"),
        "{msg}"
    );
    assert!(msg.contains("near"), "{msg}");

    // The gains count too: a fine matrix with a tiny gain is just as ill-conditioned.
    let mut cal = Calibration::identity("tiny-gain");
    cal.gains[0] = 1e-13;
    assert!(matches!(
        cal.validate().unwrap_err(),
        CalibrationError::Singular { .. }
    ));

    // Just under the limit is accepted.
    let mut cal = Calibration::identity("ok");
    cal.matrix[3][3] = 2.0 / MAX_CONDITION;
    cal.validate().unwrap();
}

#[test]
fn nan_and_inf_rejected_naming_the_field() {
    let cases = [
        ("matrix", "matrix = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, nan, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]", "matrix[2][1]", "NaN"),
        ("matrix", "matrix = [[1.0, 0.0, 0.0, -inf], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]", "matrix[0][3]", "-inf"),
        ("offsets", "offsets = [660.0, nan, 720.0, 250.0]", "offsets[1]", "NaN"),
        ("offsets", "offsets = [660.0, 440.0, 720.0, +inf]", "offsets[3]", "inf"),
        ("gains", "gains = [inf, 1.0, 1.0, 1.0]", "gains[0]", "inf"),
        ("gains", "gains = [1.0, 1.0, -nan, 1.0]", "gains[2]", "NaN"),
    ];
    for (key, line, field, shown) in cases {
        let (err, msg) = parse_err(&example_with(key, line));
        match &err {
            CalibrationError::NonFinite { field: f, .. } => assert_eq!(f, field),
            other => panic!("wrong variant for {line}: {other:?}"),
        }
        assert!(msg.contains(&format!("{field} = {shown}")), "{msg}");
    }
}

#[test]
fn zero_gain_rejected() {
    let (err, msg) = parse_err(&example_with("gains", "gains = [1.0, 0.0, 1.0, 1.0]"));
    assert!(
        matches!(err, CalibrationError::ZeroGain { channel: "D2", .. }),
        "{err:?}"
    );
    assert!(msg.contains("gain of channel D2 is zero"), "{msg}");
}

#[test]
fn offset_out_of_range_rejected() {
    let (err, msg) = parse_err(&example_with(
        "offsets",
        "offsets = [660.0, 440.0, 1024.0, 250.0]",
    ));
    assert!(
        matches!(
            err,
            CalibrationError::OffsetOutOfRange {
                channel: "D3",
                adc_max: 1023,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(
        msg.contains("D3") && msg.contains("1024") && msg.contains("0..=1023"),
        "{msg}"
    );
    let (err, _) = parse_err(&example_with(
        "offsets",
        "offsets = [-1.0, 440.0, 720.0, 250.0]",
    ));
    assert!(
        matches!(
            err,
            CalibrationError::OffsetOutOfRange { channel: "D1", .. }
        ),
        "{err:?}"
    );
    // A smaller ADC range makes the example's offsets invalid.
    let (err, msg) = parse_err(&example_with("adc_max", "adc_max = 511"));
    assert!(
        matches!(err, CalibrationError::OffsetOutOfRange { adc_max: 511, .. }),
        "{err:?}"
    );
    assert!(msg.contains("0..=511"), "{msg}");
}

#[test]
fn empty_sensor_id_and_zero_adc_max_rejected() {
    let (err, msg) = parse_err(&example_with("sensor_id", "sensor_id = \"  \""));
    assert!(
        matches!(err, CalibrationError::EmptySensorId { .. }),
        "{err:?}"
    );
    assert!(msg.contains("sensor_id is empty"), "{msg}");
    let (err, _) = parse_err(&example_with("adc_max", "adc_max = 0"));
    assert!(
        matches!(err, CalibrationError::InvalidAdcMax { .. }),
        "{err:?}"
    );
}

#[test]
fn missing_file_names_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-such-finger.toml");
    let err = Calibration::load(&path).unwrap_err();
    match &err {
        CalibrationError::Io { path: p, source } => {
            assert_eq!(p, &path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(err.to_string().contains("no-such-finger.toml"), "{err}");
}

#[test]
fn malformed_toml_names_path_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.toml");
    std::fs::write(
        &path,
        "sensor_id = \"a\"\noffsets = [1.0, 2.0,\ngains = oops\n",
    )
    .unwrap();
    let err = Calibration::load(&path).unwrap_err();
    assert!(matches!(err, CalibrationError::Parse { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("broken.toml") && msg.contains("invalid TOML") && msg.contains("line "),
        "{msg}"
    );
}

#[test]
fn wrong_shape_missing_and_unknown_fields_rejected() {
    let (err, msg) = parse_err(&example_with("gains", "gains = [1.0, 1.0, 1.0]"));
    assert!(matches!(err, CalibrationError::Parse { .. }), "{err:?}");
    assert!(msg.contains("line ") && msg.contains("length 4"), "{msg}");

    let (err, msg) = parse_err(&example_with("units", ""));
    assert!(matches!(err, CalibrationError::Parse { .. }), "{err:?}");
    assert!(msg.contains("units"), "{msg}");

    let (err, msg) = parse_err(&format!(
        "{}\ngian = 3.0\n",
        std::fs::read_to_string(example_path()).unwrap()
    ));
    assert!(matches!(err, CalibrationError::Parse { .. }), "{err:?}");
    assert!(msg.contains("gian"), "{msg}");
}

proptest! {
    #[test]
    fn prop_apply_invert_round_trip(
        raw in prop::array::uniform4(0u16..=1023),
        offsets in prop::array::uniform4(0.0f64..=1023.0),
        gains in prop::array::uniform4(prop_oneof![0.1f64..10.0, -10.0f64..-0.1]),
    ) {
        let mut cal = sample();
        cal.offsets = offsets;
        cal.gains = gains;
        let back = cal.invert(cal.apply(raw)).unwrap();
        for i in 0..4 {
            prop_assert!((back[i] - f64::from(raw[i])).abs() < 1e-6, "{:?} vs {:?}", raw, back);
        }
    }
}

#[test]
fn the_built_in_example_is_the_shipped_file() {
    assert_eq!(Calibration::example().unwrap(), example());
}
