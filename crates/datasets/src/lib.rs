//! Where the project's shared data sets live, found in one place.
//!
//! The authors' tactile recordings (`tactile/{type,width}`) and the real crack photos
//! (`cracks/…`) are not part of the repository: they sit in `../shared/data` beside the clone, or
//! wherever `$CRACKBOT_DATA_DIR` points. Product code asks [`locate`] (an error that says where it
//! looked); tests, benches and examples ask [`require`], which stops the test with one message
//! naming the missing path and how to provide it, instead of a bare "No such file or directory".
//!
//! No dependencies: any crate may use it, including as a dev-dependency.

use std::path::{Path, PathBuf};

/// Environment variable that overrides the data folder.
pub const DATA_DIR_ENV: &str = "CRACKBOT_DATA_DIR";

/// The authors' tactile recordings, surface-type experiment (`tactile/type`).
pub const TACTILE_TYPE: &str = "tactile/type";
/// The authors' tactile recordings, crack-width experiment (`tactile/width`).
pub const TACTILE_WIDTH: &str = "tactile/width";
/// Both tactile experiments (`tactile`).
pub const TACTILE: &str = "tactile";
/// The real crack photos with masks and COCO boxes (`cracks`).
pub const CRACKS: &str = "cracks";

/// The data folder: `$CRACKBOT_DATA_DIR` when set, else `../shared/data` beside the workspace.
pub fn data_dir() -> PathBuf {
    match std::env::var_os(DATA_DIR_ENV) {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
    }
}

/// A data set that is not where it should be.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingData {
    /// The path that was looked for.
    pub path: PathBuf,
}

impl std::fmt::Display for MissingData {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the shared data set {} is missing: crackbot's real-data tests and defaults need the \
             folder ../shared/data beside the clone (tactile recordings and crack photos, see \
             its README), or set {DATA_DIR_ENV} to where it is",
            self.path.display()
        )
    }
}

impl std::error::Error for MissingData {}

/// `relative` (e.g. [`TACTILE_TYPE`]) inside [`data_dir`], or an error naming the path when it
/// does not exist.
pub fn locate(relative: impl AsRef<Path>) -> Result<PathBuf, MissingData> {
    let path = data_dir().join(relative);
    if path.exists() {
        Ok(path)
    } else {
        Err(MissingData { path })
    }
}

/// Like [`locate`], for tests, benches and examples: panics with the [`MissingData`] message
/// (what is missing and how to provide it) when the data set is not there.
#[track_caller]
pub fn require(relative: impl AsRef<Path>) -> PathBuf {
    match locate(relative) {
        Ok(p) => p,
        Err(e) => panic!("{e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_data_set_names_itself_and_the_override() {
        let err = locate("no/such/data-set").unwrap_err();
        let text = err.to_string();
        assert!(text.contains("no/such/data-set"), "{text}");
        assert!(text.contains(DATA_DIR_ENV), "{text}");
        let panic = std::panic::catch_unwind(|| require("no/such/data-set"));
        assert!(panic.is_err());
    }

    #[test]
    fn the_shared_data_is_found_beside_the_workspace() {
        // The data folder is part of this machine's set-up; when it is absent the message of
        // `require` is the test's failure.
        let dir = require(TACTILE_TYPE);
        assert!(dir.is_dir());
    }
}

/// Environment variable naming the models folder (the repository's `models/`: `tactile/`,
/// `detector/`).
pub const MODELS_DIR_ENV: &str = "CRACKBOT_MODELS";

/// A deployed model, `relative` to the models folder (e.g. `tactile/recognition.ctm`):
/// under `$CRACKBOT_MODELS` when it is set (whether or not the file is there, so that an error
/// names it); else in the first `models/` beside the running binary (its folder, or one or two
/// above it, as `target/release/` of a clone) or in the working directory that holds it; else
/// under the repository this crate was built from.
pub fn model_path(relative: impl AsRef<Path>) -> PathBuf {
    let relative = relative.as_ref();
    if let Some(d) = std::env::var_os(MODELS_DIR_ENV).filter(|d| !d.is_empty()) {
        return PathBuf::from(d).join(relative);
    }
    let beside_binary = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf))
        .into_iter()
        .flat_map(|dir| {
            dir.ancestors()
                .take(3)
                .map(Path::to_path_buf)
                .collect::<Vec<_>>()
        });
    let candidates = beside_binary
        .chain(std::iter::once(PathBuf::from(".")))
        .map(|d| d.join("models").join(relative));
    let built_from = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../models")
        .join(relative);
    candidates
        .into_iter()
        .find(|p| p.exists())
        .unwrap_or(built_from)
}

#[cfg(test)]
mod model_tests {
    use super::*;

    #[test]
    fn a_model_is_found_from_anywhere_and_the_variable_wins() {
        // Found from the test binary (under the target folder, wherever it is).
        assert!(model_path("tactile/recognition.ctm").is_file());
        // The one variable, set, names the path even where nothing is (the error will say so).
        // Only this test touches the variable.
        std::env::set_var(MODELS_DIR_ENV, "/nonexistent/models");
        let p = model_path("tactile/width.ctm");
        std::env::remove_var(MODELS_DIR_ENV);
        assert_eq!(p, Path::new("/nonexistent/models/tactile/width.ctm"));
    }
}
