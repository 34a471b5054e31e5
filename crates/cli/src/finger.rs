//! `--finger PROFILE`: the finger profile a mission uses (`crackbot commission run` installs
//! them), named by its folder or by its name under the fingers' folder.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Where profiles are installed: `--fingers`, `$CRACKBOT_FINGERS`, or the user's data folder.
pub fn fingers_dir(given: Option<&Path>) -> PathBuf {
    if let Some(d) = given {
        return d.to_path_buf();
    }
    if let Some(d) = std::env::var_os("CRACKBOT_FINGERS").filter(|d| !d.is_empty()) {
        return PathBuf::from(d);
    }
    let data = std::env::var_os("XDG_DATA_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".local/share")))
        .unwrap_or_else(|| PathBuf::from("."));
    data.join("crackbot/fingers")
}

/// The profile `--finger` names: a folder, or a name under the fingers' folder.
pub fn finger_profile(arg: &Path) -> Result<crackbot_mission::commission::FingerProfile> {
    let dir = if arg.is_dir() {
        arg.to_path_buf()
    } else {
        fingers_dir(None).join(arg)
    };
    if !dir.is_dir() {
        bail!(
            "--finger {}: no such profile folder (nor {}); `crackbot commission run --name NAME` installs one",
            arg.display(),
            dir.display()
        );
    }
    crackbot_mission::commission::FingerProfile::load(&dir)
        .with_context(|| format!("the finger profile {}", dir.display()))
}
