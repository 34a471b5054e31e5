//! The `crackbot` command line end to end: demo, recording over a real PTY (interrupted, and
//! with the port vanishing), replay, calibration checks, and its errors on bad input.

use std::io::Read;
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use crackbot_tests::{binary, crackbot, csv_rows, text, Emulator};
use nix::sys::signal::{kill, Signal};
use nix::unistd::Pid;

fn json_line(out: &Output) -> serde_json::Value {
    let stdout = text(&out.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| panic!("no JSON in {stdout:?}"));
    serde_json::from_str(line).expect("summary JSON")
}

#[test]
fn demo_streams_records_and_summarises() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("demo.csv");
    let result = crackbot(&[
        "demo",
        "--seconds",
        "2",
        "--json",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(result.status.success(), "{}", text(&result.stderr));
    let summary = json_line(&result);
    assert_eq!(summary["samples"], 800);
    assert_eq!(summary["rows_written"], 800);
    assert_eq!(summary["link"]["missing_frames"], 0);
    assert!((summary["device_rate_hz"].as_f64().expect("rate") - 400.0).abs() < 1e-9);
    assert_eq!(csv_rows(&out), 800);
    // The recording replays.
    let replay = crackbot(&[
        "replay",
        out.to_str().expect("utf-8"),
        "--unpaced",
        "--json",
    ]);
    assert!(replay.status.success(), "{}", text(&replay.stderr));
    let replayed = json_line(&replay);
    assert_eq!(replayed["samples"], 800);
    assert_eq!(replayed["mean"], summary["mean"]);
}

/// Starts `crackbot record` on a fresh emulator, also logging to `mcap` when given; returns
/// both.
fn start_recording(
    out: &std::path::Path,
    mcap: Option<&std::path::Path>,
) -> (Emulator, std::process::Child) {
    let mut emulator = Emulator::spawn(&[]);
    let recorder = Command::new(binary("crackbot"))
        .args([
            "record",
            "--json",
            "--port",
            &emulator.pty,
            "--out",
            out.to_str().expect("utf-8"),
        ])
        .args(
            mcap.map(|m| ["--mcap", m.to_str().expect("utf-8")])
                .into_iter()
                .flatten(),
        )
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawning crackbot record");
    std::thread::sleep(Duration::from_millis(300));
    emulator.start();
    std::thread::sleep(Duration::from_millis(1500));
    (emulator, recorder)
}

fn finish(mut child: std::process::Child) -> (std::process::ExitStatus, String, String) {
    let mut stdout = String::new();
    let mut stderr = String::new();
    child
        .stdout
        .take()
        .expect("stdout")
        .read_to_string(&mut stdout)
        .expect("stdout");
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("stderr");
    (child.wait().expect("wait"), stdout, stderr)
}

#[test]
fn interrupted_recording_keeps_every_sample_received() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("rec.csv");
    let log = dir.path().join("rec.mcap");
    let (emulator, recorder) = start_recording(&out, Some(&log));
    kill(Pid::from_raw(recorder.id() as i32), Signal::SIGINT).expect("SIGINT");
    let (status, stdout, stderr) = finish(recorder);
    emulator.kill();
    assert!(status.success(), "Ctrl-C is a normal way to stop: {stderr}");
    let summary: serde_json::Value = serde_json::from_str(stdout.trim()).expect("summary");
    let frames = summary["link"]["frames"].as_u64().expect("frames");
    assert!(frames > 300, "{summary}");
    assert_eq!(
        summary["samples"].as_u64(),
        Some(frames),
        "every decoded frame was recorded"
    );
    assert_eq!(
        csv_rows(&out) as u64,
        frames,
        "every recorded sample is on disk"
    );
    assert!(
        stderr.contains(&format!("recorded {frames} rows")),
        "{stderr}"
    );
    // The MCAP log beside it is whole and holds the same samples, stamped in order.
    let read = crackbot_mcap::read_log(&log).expect("the MCAP log");
    let rows = crackbot_mcap::tactile_rows(&read).expect("its /tactile samples");
    assert_eq!(rows.len() as u64, frames);
    assert!(rows
        .windows(2)
        .all(|w| w[0].log_time_ns <= w[1].log_time_ns));
    let csv = crackbot_recording::read_csv(&out).expect("the CSV");
    for (r, c) in rows.iter().zip(&csv.rows) {
        assert_eq!(r.raw.map(f64::from), [c.d1, c.d2, c.d3, c.p]);
    }
}

#[test]
fn recording_survives_the_port_vanishing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("rec.csv");
    let log = dir.path().join("rec.mcap");
    let (emulator, recorder) = start_recording(&out, Some(&log));
    let pty = emulator.pty.clone();
    emulator.kill();
    let (status, stdout, stderr) = finish(recorder);
    assert!(!status.success(), "a vanished port is an error");
    assert!(
        stderr.contains("disconnected") && stderr.contains(&pty),
        "{stderr}"
    );
    let summary: serde_json::Value = serde_json::from_str(stdout.trim()).expect("summary");
    let frames = summary["link"]["frames"].as_u64().expect("frames");
    assert!(frames > 300);
    assert_eq!(csv_rows(&out) as u64, frames, "nothing received was lost");
    // Nor from the MCAP log, which was closed whole.
    let read = crackbot_mcap::read_log(&log).expect("the MCAP log");
    let logged = crackbot_mcap::tactile_rows(&read).expect("its /tactile samples");
    assert_eq!(logged.len() as u64, frames);
    // The file is complete, not cut mid-line: it reads back.
    let replay = crackbot(&[
        "replay",
        out.to_str().expect("utf-8"),
        "--unpaced",
        "--json",
    ]);
    assert!(replay.status.success(), "{}", text(&replay.stderr));
}

#[test]
fn recording_from_a_missing_port_is_a_clear_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("rec.csv");
    let result = crackbot(&[
        "record",
        "--port",
        "/dev/ttyNOPE7",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!result.status.success());
    let err = text(&result.stderr);
    assert!(
        err.contains("/dev/ttyNOPE7") && err.contains("does not exist"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_truncated_recording_is_a_clear_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("demo.csv");
    let path = out.to_str().expect("utf-8");
    assert!(
        crackbot(&["demo", "--seconds", "0.5", "--json", "--out", path])
            .status
            .success()
    );
    let bytes = std::fs::read(&out).expect("read");
    std::fs::write(&out, &bytes[..bytes.len() - 7]).expect("truncate");
    let result = crackbot(&["replay", path, "--unpaced"]);
    assert!(!result.status.success());
    let err = text(&result.stderr);
    assert!(err.contains(path) && err.contains("truncated"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn calibration_check_accepts_the_example_and_rejects_degenerate_files() {
    let example = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/crates/acquisition/calibration/example.toml"
    );
    let ok = crackbot(&["calibration", "check", example]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
    assert!(text(&ok.stdout).contains("OK"));

    let dir = tempfile::tempdir().expect("temp dir");
    let good = std::fs::read_to_string(example).expect("example");
    let cases = [
        // Two identical rows: singular.
        ("singular.toml", "matrix = [[1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]", "singular"),
        ("nan.toml", "matrix = [[nan, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]", "matrix[0][0]"),
    ];
    for (name, matrix, expected) in cases {
        let path = dir.path().join(name);
        let text_in: String = replace_matrix(&good, matrix);
        std::fs::write(&path, text_in).expect("write");
        let result = crackbot(&["calibration", "check", path.to_str().expect("utf-8")]);
        assert!(!result.status.success(), "{name} accepted");
        let err = text(&result.stderr);
        assert!(
            err.contains(name) && err.contains(expected),
            "{name}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// Replaces the `matrix = [...]` entry (possibly spanning lines) of a calibration file.
fn replace_matrix(toml: &str, matrix: &str) -> String {
    let start = toml.find("\nmatrix").expect("matrix key") + 1;
    let mut depth = 0;
    let mut end = start;
    for (i, c) in toml[start..].char_indices() {
        match c {
            '[' => depth += 1,
            ']' => {
                depth -= 1;
                if depth == 0 {
                    end = start + i + 1;
                    break;
                }
            }
            _ => {}
        }
    }
    format!("{}{}{}", &toml[..start], matrix, &toml[end..])
}
