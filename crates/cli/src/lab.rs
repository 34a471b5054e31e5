//! The research commands, handed to `crackbot-lab` (as `git` and `cargo` hand their external
//! subcommands to `git-x` and `cargo-x`): `crackbot tactile eval …` runs `crackbot-lab tactile
//! eval …` with the same arguments, standard streams and exit status, so the operator's binary
//! never compiles the research dependencies and every research command still works from here.

use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::Command;

use anyhow::{bail, Context, Result};
use clap::Args;

/// The research binary.
pub const LAB: &str = "crackbot-lab";

/// Whatever follows the command name, passed on untouched (`--help` included).
#[derive(Debug, Args)]
pub struct Forwarded {
    #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
    args: Vec<OsString>,
}

/// Where `crackbot-lab` is: beside this executable (one build of the workspace), else on `PATH`.
fn lab_executable() -> Option<PathBuf> {
    let beside = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(|dir| dir.join(LAB)))
        .filter(|p| p.is_file());
    beside.or_else(|| {
        std::env::var_os("PATH").and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|dir| dir.join(LAB))
                .find(|p| p.is_file())
        })
    })
}

/// Replaces this process with `crackbot-lab <command> <args…>` (same standard streams, signals
/// and exit status); returns only when that cannot be started.
pub fn run(command: &str, forwarded: Forwarded) -> Result<()> {
    let Some(lab) = lab_executable() else {
        bail!(
            "`crackbot {command}` is a research command of {LAB}, which is not built: run \
             `cargo build --release -p crackbot-lab` (or put {LAB} on PATH), then \
             `crackbot {command} …` or `{LAB} {command} …`"
        );
    };
    // argv[0] is what the user typed, so help and errors say `crackbot tactile eval`.
    let error = Command::new(&lab)
        .arg0("crackbot")
        .arg(command)
        .args(&forwarded.args)
        .exec();
    Err(error).with_context(|| format!("running {}", lab.display()))
}
