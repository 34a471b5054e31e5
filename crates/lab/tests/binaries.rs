//! `crackbot-lab` starts, lists its research commands and refuses an unknown one by name.
//!
//! Being this package's integration test also makes `cargo test` build `crackbot-lab` in its
//! own build graph, so the workspace's end-to-end tests (`tests/support`) find it built.

use std::process::Command;

#[test]
fn the_lab_lists_its_commands_and_names_an_unknown_one() {
    let exe = env!("CARGO_BIN_EXE_crackbot-lab");
    let out = Command::new(exe)
        .arg("--help")
        .output()
        .expect("running crackbot-lab");
    assert!(out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    for command in [
        "tactile",
        "eval-detector",
        "detector-tradeoff",
        "sim",
        "mission",
    ] {
        assert!(stdout.contains(command), "no {command} in {stdout}");
    }
    let out = Command::new(exe)
        .arg("no-such-command")
        .output()
        .expect("running crackbot-lab");
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no-such-command"), "{stderr}");
}
