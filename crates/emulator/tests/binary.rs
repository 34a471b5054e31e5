//! `crackbot-sensor-emulator` starts, describes its outputs and refuses a bad baud rate by name.
//!
//! Being this package's integration test also makes `cargo test` build the emulator binary in
//! its own build graph, so the workspace's end-to-end tests (`tests/support`) find it built.

use std::process::Command;

#[test]
fn the_emulator_describes_its_outputs_and_names_a_bad_flag_value() {
    let exe = env!("CARGO_BIN_EXE_crackbot-sensor-emulator");
    let out = Command::new(exe)
        .arg("--help")
        .output()
        .expect("running the emulator");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    for flag in ["--pty", "--port", "--baud"] {
        assert!(stdout.contains(flag), "no {flag} in {stdout}");
    }
    let out = Command::new(exe)
        .args(["--pty", "--baud", "fast"])
        .output()
        .expect("running the emulator");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--baud") && stderr.contains("fast"),
        "{stderr}"
    );
}
