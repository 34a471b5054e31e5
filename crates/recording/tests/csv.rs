//! Tests of the CSV reader, writer and streaming recorder.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::{Path, PathBuf};

use crackbot_recording::{
    read_csv, read_csv_from, write_csv, CsvRecorder, Extra, Recording, RecordingError, Row,
    COLUMNS, EXTRA_COLUMNS,
};
use crackbot_testkit::assert_bits_equal;
use proptest::prelude::*;

const HEADER: &str = "x_mm,d1,d2,d3,p,direction,slide,label,repetition\n";
const GOOD_LINE: &str = "7.8,660,440,720,250,1,1,0,1\n";

fn sample_row(i: u32) -> Row {
    Row {
        x_mm: 7.8 + f64::from(i) * 0.01,
        d1: 660.0,
        d2: 441.5,
        d3: 720.25,
        p: 250.0 + f64::from(i),
        direction: (i % 2) as u8,
        slide: 1 + i / 10,
        label: 2.0,
        repetition: 3,
    }
}

/// Writes `content` to a file named `name` in a fresh temporary directory.
fn write_file(name: &str, content: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, content).unwrap();
    (dir, path)
}

/// Reads `content` from a file and returns the error, checking that its message names the file.
fn read_err(content: &str) -> (RecordingError, String) {
    let (_dir, path) = write_file("bad_recording.csv", content.as_bytes());
    let err = read_csv(&path).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "message does not name the file: {msg}"
    );
    (err, msg)
}

#[test]
fn column_constants() {
    assert_eq!(COLUMNS.len(), 9);
    assert_eq!(EXTRA_COLUMNS, ["device_time_us", "seq", "flags"]);
}

#[test]
fn reads_basic_file() {
    let text = format!("{HEADER}{GOOD_LINE}7.9,661.5,439,721,251,0,2,1.5,1\n");
    let rec = read_csv_from(text.as_bytes(), "mem.csv").unwrap();
    assert_eq!(rec.len(), 2);
    assert!(!rec.is_empty());
    assert!(rec.extra.is_none());
    assert_eq!(
        rec.rows[1],
        Row {
            x_mm: 7.9,
            d1: 661.5,
            d2: 439.0,
            d3: 721.0,
            p: 251.0,
            direction: 0,
            slide: 2,
            label: 1.5,
            repetition: 1
        }
    );
}

#[test]
fn reads_extended_file_and_float_integers() {
    let text = "x_mm,d1,d2,d3,p,direction,slide,label,repetition,device_time_us,seq,flags\n\
                7.8,660,440,720,250,1.0,3.0,0,2.0,18446744073709551615,65535,255\n";
    let rec = read_csv_from(text.as_bytes(), "mem.csv").unwrap();
    assert_eq!(rec.rows[0].slide, 3);
    assert_eq!(rec.rows[0].repetition, 2);
    assert_eq!(rec.rows[0].direction, 1);
    assert_eq!(
        rec.extra.unwrap(),
        vec![Extra {
            device_time_us: u64::MAX,
            seq: 65535,
            flags: 255
        }]
    );
}

#[test]
fn header_only_is_empty_recording() {
    let rec = read_csv_from(HEADER.as_bytes(), "mem.csv").unwrap();
    assert!(rec.is_empty());
    assert_eq!(rec.len(), 0);
}

#[test]
fn crlf_line_endings_are_accepted() {
    let text = format!(
        "{}{}",
        HEADER.replace('\n', "\r\n"),
        GOOD_LINE.replace('\n', "\r\n")
    );
    let rec = read_csv_from(text.as_bytes(), "mem.csv").unwrap();
    assert_eq!(rec.len(), 1);
}

#[test]
fn error_missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no_such_recording.csv");
    let err = read_csv(&path).unwrap_err();
    match &err {
        RecordingError::Io { path: p, source } => {
            assert_eq!(p, &path);
            assert_eq!(source.kind(), std::io::ErrorKind::NotFound);
        }
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(err.to_string().contains("no_such_recording.csv"));
}

#[test]
fn error_empty_file() {
    let (err, msg) = read_err("");
    assert!(matches!(err, RecordingError::Empty { .. }), "{err:?}");
    assert!(msg.contains("empty"), "{msg}");
}

#[test]
fn error_wrong_header() {
    let (err, msg) = read_err("x_mm,d1,d2,d4,p,direction,slide,label,repetition\n");
    match &err {
        RecordingError::Header {
            column,
            expected,
            found,
            ..
        } => {
            assert_eq!(*column, 4);
            assert_eq!(expected, "d3");
            assert_eq!(found, "d4");
        }
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(msg.contains("`d3`") && msg.contains("`d4`"), "{msg}");
}

#[test]
fn error_short_and_long_headers() {
    let (err, msg) = read_err("x_mm,d1,d2,d3,p,direction,slide,label\n");
    assert!(
        matches!(err, RecordingError::Header { column: 9, .. }),
        "{err:?}"
    );
    assert!(
        msg.contains("repetition") && msg.contains("<missing>"),
        "{msg}"
    );

    let (err, msg) = read_err("x_mm,d1,d2,d3,p,direction,slide,label,repetition,device_time_us\n");
    assert!(
        matches!(err, RecordingError::Header { column: 11, .. }),
        "{err:?}"
    );
    assert!(msg.contains("seq"), "{msg}");

    let (err, msg) = read_err(
        "x_mm,d1,d2,d3,p,direction,slide,label,repetition,device_time_us,seq,flags,more\n",
    );
    assert!(
        matches!(err, RecordingError::Header { column: 13, .. }),
        "{err:?}"
    );
    assert!(msg.contains("more"), "{msg}");
}

#[test]
fn error_field_count() {
    let (err, msg) = read_err(&format!("{HEADER}{GOOD_LINE}7.8,660,440,720,250,1,1,0\n"));
    match &err {
        RecordingError::FieldCount {
            line,
            expected,
            found,
            ..
        } => {
            assert_eq!((*line, *expected, *found), (3, 9, 8));
        }
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(
        msg.contains("line 3") && msg.contains("expected 9") && msg.contains("found 8"),
        "{msg}"
    );
}

#[test]
fn error_unparseable_value() {
    let (err, msg) = read_err(&format!(
        "{HEADER}{GOOD_LINE}{GOOD_LINE}7.8,660,44x0,720,250,1,1,0,1\n"
    ));
    match &err {
        RecordingError::InvalidValue {
            line, column, text, ..
        } => {
            assert_eq!((*line, *column, text.as_str()), (4, "d2", "44x0"));
        }
        other => panic!("wrong variant: {other:?}"),
    }
    assert!(
        msg.contains("line 4") && msg.contains("`d2`") && msg.contains("44x0"),
        "{msg}"
    );
}

#[test]
fn error_non_finite() {
    for (text, column) in [("NaN", "d1"), ("inf", "d1"), ("-inf", "d1")] {
        let (err, msg) = read_err(&format!("{HEADER}7.8,{text},440,720,250,1,1,0,1\n"));
        match &err {
            RecordingError::NonFinite {
                line, column: c, ..
            } => {
                assert_eq!((*line, *c), (2, column));
            }
            other => panic!("wrong variant: {other:?}"),
        }
        assert!(
            msg.contains("line 2") && msg.contains("`d1`") && msg.contains(text),
            "{msg}"
        );
    }
    let (err, msg) = read_err(&format!("{HEADER}7.8,660,440,720,250,1,1,NaN,1\n"));
    assert!(
        matches!(
            err,
            RecordingError::NonFinite {
                column: "label",
                ..
            }
        ),
        "{err:?}"
    );
    assert!(msg.contains("label"), "{msg}");
}

#[test]
fn error_bad_direction() {
    for text in ["2", "0.5", "-1"] {
        let (err, msg) = read_err(&format!("{HEADER}7.8,660,440,720,250,{text},1,0,1\n"));
        assert!(
            matches!(err, RecordingError::InvalidDirection { line: 2, .. }),
            "{err:?}"
        );
        assert!(
            msg.contains("direction") && msg.contains("0 or 1") && msg.contains(text),
            "{msg}"
        );
    }
}

#[test]
fn error_negative_or_fractional_slide_and_repetition() {
    let cases = [
        ("7.8,660,440,720,250,1,-1,0,1\n", "slide", "-1"),
        ("7.8,660,440,720,250,1,1.5,0,1\n", "slide", "1.5"),
        (
            "7.8,660,440,720,250,1,4294967296,0,1\n",
            "slide",
            "4294967296",
        ),
        ("7.8,660,440,720,250,1,1,0,-3\n", "repetition", "-3"),
        ("7.8,660,440,720,250,1,1,0,2.25\n", "repetition", "2.25"),
    ];
    for (line, column, text) in cases {
        let (err, msg) = read_err(&format!("{HEADER}{line}"));
        match &err {
            RecordingError::InvalidInteger {
                line,
                column: c,
                text: t,
                ..
            } => {
                assert_eq!((*line, *c, t.as_str()), (2, column, text));
            }
            other => panic!("wrong variant: {other:?}"),
        }
        assert!(
            msg.contains(column) && msg.contains(text) && msg.contains("line 2"),
            "{msg}"
        );
    }
}

#[test]
fn error_bad_extra_value() {
    let head = "x_mm,d1,d2,d3,p,direction,slide,label,repetition,device_time_us,seq,flags\n";
    let (err, msg) = read_err(&format!("{head}7.8,660,440,720,250,1,1,0,1,100,65536,0\n"));
    assert!(
        matches!(
            err,
            RecordingError::InvalidInteger {
                column: "seq",
                max: 65535,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(msg.contains("seq") && msg.contains("65536"), "{msg}");
    let (err, _) = read_err(&format!("{head}7.8,660,440,720,250,1,1,0,1,abc,1,0\n"));
    assert!(
        matches!(
            err,
            RecordingError::InvalidValue {
                column: "device_time_us",
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn error_truncated_even_if_last_line_parses() {
    // The partial last line happens to be a complete, valid row: still truncated.
    let (err, msg) = read_err(&format!("{HEADER}{GOOD_LINE}{}", GOOD_LINE.trim_end()));
    assert!(
        matches!(err, RecordingError::Truncated { line: 3, .. }),
        "{err:?}"
    );
    assert!(
        msg.contains("ends mid-line at line 3") && msg.contains("truncated"),
        "{msg}"
    );

    // Cut in the middle of a number.
    let (err, _) = read_err(&format!("{HEADER}{GOOD_LINE}7.8,66"));
    assert!(
        matches!(err, RecordingError::Truncated { line: 3, .. }),
        "{err:?}"
    );

    // Even the header alone, unterminated.
    let (err, _) = read_err(HEADER.trim_end());
    assert!(
        matches!(err, RecordingError::Truncated { line: 1, .. }),
        "{err:?}"
    );
}

#[test]
fn error_invalid_utf8() {
    let mut bytes = HEADER.as_bytes().to_vec();
    bytes.extend_from_slice(b"7.8,6\xff0,440,720,250,1,1,0,1\n");
    let (_dir, path) = write_file("utf8.csv", &bytes);
    let err = read_csv(&path).unwrap_err();
    assert!(matches!(err, RecordingError::Csv { .. }), "{err:?}");
    assert!(err.to_string().contains("utf8.csv"), "{err}");
}

#[test]
fn read_from_names_source() {
    let err = read_csv_from(&b""[..], "serial-capture").unwrap_err();
    assert!(err.to_string().contains("serial-capture"), "{err}");
}

#[test]
fn validate_catches_bad_rows_and_extra_length() {
    let mut rec = Recording {
        rows: vec![sample_row(0), sample_row(1)],
        extra: None,
    };
    rec.validate().unwrap();
    rec.rows[1].d3 = f64::NAN;
    let err = rec.validate().unwrap_err();
    assert!(
        matches!(
            err,
            RecordingError::InvalidRow {
                index: 1,
                column: "d3",
                ..
            }
        ),
        "{err:?}"
    );
    rec.rows[1].d3 = 1.0;
    rec.rows[0].direction = 2;
    assert!(matches!(
        rec.validate().unwrap_err(),
        RecordingError::InvalidRow {
            index: 0,
            column: "direction",
            ..
        }
    ));
    rec.rows[0].direction = 0;
    rec.extra = Some(vec![Extra::default()]);
    let err = rec.validate().unwrap_err();
    assert!(
        matches!(err, RecordingError::ExtraLength { rows: 2, extra: 1 }),
        "{err:?}"
    );
}

#[test]
fn write_csv_refuses_invalid_data() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("refused.csv");
    let mut row = sample_row(0);
    row.p = f64::INFINITY;
    let rec = Recording {
        rows: vec![row],
        extra: None,
    };
    let err = write_csv(&path, &rec).unwrap_err();
    assert!(matches!(err, RecordingError::InvalidData { .. }), "{err:?}");
    assert!(
        err.to_string().contains("refused.csv") && err.to_string().contains("`p`"),
        "{err}"
    );
    assert!(!path.exists());
}

#[test]
fn write_csv_format() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.csv");
    let rec = Recording {
        rows: vec![sample_row(0)],
        extra: Some(vec![Extra {
            device_time_us: 2500,
            seq: 1,
            flags: 0,
        }]),
    };
    write_csv(&path, &rec).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert_eq!(
        text,
        "x_mm,d1,d2,d3,p,direction,slide,label,repetition,device_time_us,seq,flags\n\
         7.8,660,441.5,720.25,250,0,1,2,3,2500,1,0\n"
    );
}

#[test]
fn recorder_flushes_on_drop() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("live.csv");
    {
        let mut rec = CsvRecorder::create(&path, false).unwrap();
        assert_eq!(rec.path(), path.as_path());
        for i in 0..1000 {
            rec.append(&sample_row(i), None).unwrap();
        }
        assert_eq!(rec.rows_written(), 1000);
        // Dropped without finish().
    }
    let back = read_csv(&path).unwrap();
    assert_eq!(back.len(), 1000);
    assert_eq!(back.rows[999], sample_row(999));
    assert!(back.extra.is_none());
}

#[test]
fn recorder_flush_makes_rows_visible() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("live.csv");
    let mut rec = CsvRecorder::create(&path, false).unwrap();
    rec.append(&sample_row(0), None).unwrap();
    rec.flush().unwrap();
    // While the recorder is still open, the file is complete up to the last flushed row.
    assert_eq!(read_csv(&path).unwrap().len(), 1);
    rec.append(&sample_row(1), None).unwrap();
    assert_eq!(rec.finish().unwrap(), 2);
    assert_eq!(read_csv(&path).unwrap().len(), 2);
}

#[test]
fn recorder_extended_finish_returns_count() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("live_ext.csv");
    let mut rec = CsvRecorder::create(&path, true).unwrap();
    for i in 0..5u32 {
        let extra = Extra {
            device_time_us: u64::from(i) * 2500,
            seq: i as u16,
            flags: 1,
        };
        rec.append(&sample_row(i), Some(&extra)).unwrap();
    }
    // Extended recorder requires extras; the refused row is not written.
    let err = rec.append(&sample_row(9), None).unwrap_err();
    assert!(
        matches!(err, RecordingError::MissingExtra { row: 5, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("live_ext.csv"));
    // Invalid rows are refused too.
    let mut bad = sample_row(9);
    bad.x_mm = f64::NAN;
    let err = rec.append(&bad, Some(&Extra::default())).unwrap_err();
    assert!(matches!(err, RecordingError::InvalidData { .. }), "{err:?}");
    assert_eq!(rec.finish().unwrap(), 5);
    let back = read_csv(&path).unwrap();
    assert_eq!(back.len(), 5);
    assert_eq!(back.extra.as_ref().unwrap()[4].device_time_us, 10_000);
}

#[test]
fn recorder_create_error_names_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("missing_dir").join("live.csv");
    let err = CsvRecorder::create(&path, false).unwrap_err();
    assert!(matches!(err, RecordingError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("missing_dir"), "{err}");
}

fn finite_f64() -> impl Strategy<Value = f64> {
    prop::num::f64::POSITIVE
        | prop::num::f64::NEGATIVE
        | prop::num::f64::NORMAL
        | prop::num::f64::SUBNORMAL
        | prop::num::f64::ZERO
}

prop_compose! {
    fn arb_row()(
        x_mm in finite_f64(), d1 in finite_f64(), d2 in finite_f64(), d3 in finite_f64(), p in finite_f64(),
        direction in 0u8..=1, slide in any::<u32>(), label in finite_f64(), repetition in any::<u32>(),
    ) -> Row {
        Row { x_mm, d1, d2, d3, p, direction, slide, label, repetition }
    }
}

prop_compose! {
    fn arb_extra()(device_time_us in any::<u64>(), seq in any::<u16>(), flags in any::<u8>()) -> Extra {
        Extra { device_time_us, seq, flags }
    }
}

fn arb_recording() -> impl Strategy<Value = Recording> {
    (
        prop::collection::vec((arb_row(), arb_extra()), 0..40),
        any::<bool>(),
    )
        .prop_map(|(pairs, extended)| {
            let (rows, extras): (Vec<Row>, Vec<Extra>) = pairs.into_iter().unzip();
            Recording {
                rows,
                extra: extended.then_some(extras),
            }
        })
}

fn round_trip(path: &Path, rec: &Recording) -> Recording {
    write_csv(path, rec).unwrap();
    read_csv(path).unwrap()
}

proptest! {
    #[test]
    fn prop_round_trip_write_read(rec in arb_recording()) {
        prop_assert!(rec.validate().is_ok());
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rt.csv");
        let back = round_trip(&path, &rec);
        assert_bits_equal(&rec, &back, "round trip");
    }

    #[test]
    fn prop_round_trip_recorder(rec in arb_recording()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rt_live.csv");
        let mut recorder = CsvRecorder::create(&path, rec.extra.is_some()).unwrap();
        for (i, row) in rec.rows.iter().enumerate() {
            recorder.append(row, rec.extra.as_ref().map(|e| &e[i])).unwrap();
        }
        prop_assert_eq!(recorder.finish().unwrap(), rec.len() as u64);
        let back = read_csv(&path).unwrap();
        assert_bits_equal(&rec, &back, "round trip");
    }
}

#[test]
fn write_to_unwritable_path_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nope").join("x.csv");
    let err = write_csv(&path, &Recording::default()).unwrap_err();
    assert!(err.to_string().contains("nope"), "{err}");
}
