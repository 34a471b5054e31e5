//! Where the trained detector is: the default model file of this repository, found from the
//! working directory or, for a binary built from this repository, from its source tree.

use std::path::{Path, PathBuf};

/// The default model, relative to the repository root.
pub const DEFAULT_MODEL: &str = "models/detector/crack-detector-320.onnx";

/// The input sizes of the models trained in `models/detector/` (`crack-detector-<size>.onnx`).
pub const TRAINED_INPUT_SIZES: [usize; 3] = [256, 320, 416];

/// The default model: [`DEFAULT_MODEL`] under the working directory when it is there, else under
/// the repository this crate was built from.
pub fn default_model() -> PathBuf {
    let here = PathBuf::from(DEFAULT_MODEL);
    if here.is_file() {
        return here;
    }
    // A binary built from this repository also finds the model from elsewhere.
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(DEFAULT_MODEL)
}

/// The model to load: `explicit` when given, else [`default_model`].
pub fn resolve_model(explicit: Option<&Path>) -> PathBuf {
    explicit.map_or_else(default_model, Path::to_path_buf)
}

/// The trained models of every size in [`TRAINED_INPUT_SIZES`], beside [`default_model`].
pub fn trained_models() -> Vec<PathBuf> {
    TRAINED_INPUT_SIZES
        .iter()
        .map(|s| default_model().with_file_name(format!("crack-detector-{s}.onnx")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_model_is_found_from_anywhere() {
        assert!(default_model().is_file(), "{}", default_model().display());
        assert_eq!(
            resolve_model(Some(Path::new("x.onnx"))),
            PathBuf::from("x.onnx")
        );
        let all = trained_models();
        assert_eq!(all.len(), 3);
        assert!(all[1].ends_with("crack-detector-320.onnx"));
    }
}
