//! Helpers for the workspace's integration tests: build and locate the binaries, drive the
//! sensor emulator on a real pseudo-terminal.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::{Mutex, OnceLock};

/// The features every test build has (`scripts/test.sh`'s): the robot's fleet telemetry and
/// Foxglove live view, its live ROS 2 topics, and the controller's ROS 2 arm.
pub const FEATURES: &str =
    "crackbot-cli/telemetry,crackbot-cli/foxglove,crackbot-cli/ros2,crackbot-controller/ros2";

/// Path of a workspace binary, built (once per test process) with the profile of the running
/// test, so `cargo test` alone is enough. Every test gets the binaries built with the robot's
/// fleet telemetry and Foxglove live view (`crackbot-cli/telemetry,foxglove`: they only add
/// flags), so that no two tests rebuild
/// them with different features. `crackbot` comes with `crackbot-lab` beside it, which
/// runs the research commands `crackbot` hands on.
pub fn binary(name: &str) -> PathBuf {
    static BUILT: OnceLock<Mutex<Vec<String>>> = OnceLock::new();
    let exe = std::env::current_exe().expect("test executable path");
    // target/<profile>/deps/<test> → target/<profile>
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile>")
        .to_path_buf();
    let target_dir = profile_dir.parent().expect("target dir").to_path_buf();
    let release = profile_dir.file_name().is_some_and(|n| n == "release");
    let built = BUILT.get_or_init(|| Mutex::new(Vec::new()));
    let mut built = built
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if !built.iter().any(|b| b == name) {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut cmd = Command::new(cargo);
        // One test target (`--test layering`, small) and the telemetry feature make this build
        // resolve features exactly as `scripts/test.sh` does (`cargo test --workspace --features
        // crackbot-cli/telemetry`: dev-dependencies on), so it reuses what the test run compiled
        // instead of building tokio, rand and everything above them again with other features.
        cmd.args([
            "build",
            "--quiet",
            "--workspace",
            "--test",
            "layering",
            "--bin",
            name,
        ]);
        cmd.args(["--features", FEATURES]);
        if name == "crackbot" {
            cmd.args(["--bin", "crackbot-lab"]);
        }
        cmd.arg("--target-dir").arg(&target_dir);
        if release {
            cmd.arg("--release");
        }
        cmd.current_dir(env!("CARGO_MANIFEST_DIR"));
        clear_test_env(&mut cmd);
        let status = cmd.status().expect("running cargo build");
        assert!(status.success(), "cargo build --bin {name} failed");
        built.push(name.to_string());
    }
    profile_dir.join(name)
}

/// Removes the variables cargo (or nextest) sets for a running test, so that the nested `cargo
/// build` sees the environment `scripts/test.sh`'s own build saw. Build scripts watch some of them
/// (`ring`'s watches `CARGO_MANIFEST_DIR`): inherited, they made this build rerun `ring` and
/// rebuild everything above it (rustls, Zenoh, the robot) once per test run, and the test run's
/// next build rebuild it all back.
fn clear_test_env(cmd: &mut Command) {
    const SET_FOR_TESTS: &[&str] = &[
        "CARGO_MANIFEST_DIR",
        "CARGO_MANIFEST_PATH",
        "CARGO_CRATE_NAME",
        "CARGO_BIN_NAME",
        "CARGO_PRIMARY_PACKAGE",
        "CARGO_TARGET_TMPDIR",
        "CARGO_RUSTC_CURRENT_DIR",
        "OUT_DIR",
    ];
    for (key, _) in std::env::vars_os() {
        let Some(key) = key.to_str() else { continue };
        if SET_FOR_TESTS.contains(&key)
            || key.starts_with("CARGO_PKG_")
            || key.starts_with("CARGO_BIN_EXE_")
            || key.starts_with("NEXTEST")
        {
            cmd.env_remove(key);
        }
    }
}

/// A running `crackbot-sensor-emulator --pty --wait-for-start`.
pub struct Emulator {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<std::process::ChildStdout>,
    /// Device path of the pseudo-terminal it writes to.
    pub pty: String,
}

impl Emulator {
    /// Spawns the emulator with extra arguments and waits until it has printed its PTY path.
    pub fn spawn(args: &[&str]) -> Emulator {
        let mut child = Command::new(binary("crackbot-sensor-emulator"))
            .args(["--pty", "--wait-for-start"])
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("spawning the emulator");
        let stdin = child.stdin.take();
        let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
        let mut line = String::new();
        stdout.read_line(&mut line).expect("reading the PTY line");
        let pty = line
            .trim()
            .strip_prefix("PTY ")
            .unwrap_or_else(|| panic!("unexpected first line {line:?}"))
            .to_string();
        Emulator {
            child,
            stdin,
            stdout,
            pty,
        }
    }

    /// Lets it start streaming.
    pub fn start(&mut self) {
        let mut stdin = self.stdin.take().expect("started twice");
        stdin.write_all(b"go\n").expect("starting the emulator");
    }

    /// Waits for it to finish; returns its JSON report.
    pub fn wait(mut self) -> serde_json::Value {
        let mut line = String::new();
        self.stdout
            .read_line(&mut line)
            .expect("reading the report");
        let status = self.child.wait().expect("waiting for the emulator");
        assert!(status.success(), "emulator failed: {status}");
        serde_json::from_str(&line).unwrap_or_else(|e| panic!("bad report {line:?}: {e}"))
    }

    /// Kills it at once (the PTY disappears).
    pub fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }
}

/// Runs the `crackbot` binary with `args` to completion.
pub fn crackbot(args: &[&str]) -> std::process::Output {
    Command::new(binary("crackbot"))
        .args(args)
        .output()
        .expect("running crackbot")
}

/// Lossy UTF-8 of a process's output.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Number of data rows (lines after the header) of a CSV file.
pub fn csv_rows(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).expect("reading the CSV");
    text.lines().count().saturating_sub(1)
}

/// Reads `stream` until it ends (or errs) and returns the samples, the error that ended it and
/// the link statistics; fails the test if that takes longer than `limit`.
pub fn read_all(
    stream: &mut crackbot_acquisition::SensorStream,
    limit: std::time::Duration,
) -> (
    Vec<crackbot_acquisition::Sample>,
    Option<crackbot_acquisition::AcquisitionError>,
    crackbot_acquisition::LinkStats,
) {
    let start = std::time::Instant::now();
    let mut samples = Vec::new();
    let mut error = None;
    while let Some(item) = stream.blocking_next() {
        match item {
            Ok(s) => samples.push(s),
            Err(e) => {
                error = Some(e);
                break;
            }
        }
        assert!(
            start.elapsed() < limit,
            "stream did not end within {limit:?}"
        );
    }
    (samples, error, stream.stats())
}

/// The confirmed cracks' positions in a robot's JSON report, sorted by x.
pub fn confirmed(stdout: &[u8]) -> Vec<[f64; 2]> {
    let report: serde_json::Value = serde_json::from_slice(stdout).expect("one JSON object");
    let mut at: Vec<[f64; 2]> = report["cracks"]
        .as_array()
        .expect("cracks")
        .iter()
        .map(|c| serde_json::from_value(c["position_mm"].clone()).expect("position_mm"))
        .collect();
    at.sort_by(|a, b| a[0].total_cmp(&b[0]));
    at
}
