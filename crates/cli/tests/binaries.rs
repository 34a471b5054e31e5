//! The robot's two binaries start, describe themselves and refuse an unknown flag by name.
//!
//! Being this package's integration test also makes `cargo test` build `crackbot` and
//! `crackbot-robot` in its own build graph, beside everything else, so the workspace's
//! end-to-end tests (`tests/support`) find them built instead of linking them one by one.

use std::process::Command;

fn run(exe: &str, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("running {exe}: {e}"));
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.success(), text(&out.stdout), text(&out.stderr))
}

#[test]
fn crackbot_lists_its_commands() {
    let (ok, stdout, _) = run(env!("CARGO_BIN_EXE_crackbot"), &["--help"]);
    assert!(ok);
    for command in ["run", "record", "replay", "detect", "homography"] {
        assert!(stdout.contains(command), "no {command} in {stdout}");
    }
    let (ok, _, stderr) = run(env!("CARGO_BIN_EXE_crackbot"), &["no-such-command"]);
    assert!(!ok);
    assert!(stderr.contains("no-such-command"), "{stderr}");
}

#[test]
fn the_robot_lists_its_flags_and_names_an_unknown_one() {
    let (ok, stdout, _) = run(env!("CARGO_BIN_EXE_crackbot-robot"), &["--help"]);
    assert!(ok);
    for flag in ["--mode", "--json", "--site"] {
        assert!(stdout.contains(flag), "no {flag} in {stdout}");
    }
    let (ok, _, stderr) = run(env!("CARGO_BIN_EXE_crackbot-robot"), &["--no-such-flag"]);
    assert!(!ok);
    assert!(stderr.contains("--no-such-flag"), "{stderr}");
}
