//! Which detector to run and where the trained one is: the default model file of this
//! repository, found from the working directory or, for a binary built from this repository, from
//! its source tree.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::classical::{ClassicalDetector, ClassicalParams};
use crate::preprocess::PostprocessParams;
use crate::{Detector, VisionError};

/// The detectors crackbot has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectorKind {
    /// The trained model, through ONNX Runtime (feature `onnx`).
    #[default]
    Onnx,
    /// The edge-based baseline (no model).
    Classical,
}

impl DetectorKind {
    /// Every detector, in the order of [`DetectorKind::name`].
    pub const ALL: [DetectorKind; 2] = [DetectorKind::Onnx, DetectorKind::Classical];

    /// `"onnx"` or `"classical"`, as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            DetectorKind::Onnx => "onnx",
            DetectorKind::Classical => "classical",
        }
    }
}

impl std::fmt::Display for DetectorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for DetectorKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DetectorKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown detector {s:?}: use `onnx` (the trained model) or `classical` (the edge-based baseline)"))
    }
}

/// A detector to build: which one, which model file, how many ONNX Runtime threads (default: the
/// trained default model on one thread).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectorChoice {
    /// Which detector.
    pub kind: DetectorKind,
    /// The ONNX model (`None`: [`default_model`]).
    pub model: Option<PathBuf>,
    /// ONNX Runtime intra-op threads.
    pub threads: usize,
}

impl Default for DetectorChoice {
    fn default() -> Self {
        DetectorChoice {
            kind: DetectorKind::Onnx,
            model: None,
            threads: 1,
        }
    }
}

/// Builds the detector `choice` names, with `params` for its post-processing.
pub fn build_detector(
    choice: &DetectorChoice,
    params: PostprocessParams,
) -> Result<Box<dyn Detector>, VisionError> {
    match choice.kind {
        DetectorKind::Onnx => onnx_detector(choice, params),
        DetectorKind::Classical => Ok(Box::new(
            ClassicalDetector::new(ClassicalParams::default())?,
        )),
    }
}

#[cfg(feature = "onnx")]
fn onnx_detector(
    choice: &DetectorChoice,
    params: PostprocessParams,
) -> Result<Box<dyn Detector>, VisionError> {
    let path = resolve_model(choice.model.as_deref());
    Ok(Box::new(crate::onnx::OnnxDetector::load(
        &path,
        params,
        choice.threads,
    )?))
}

#[cfg(not(feature = "onnx"))]
fn onnx_detector(
    _choice: &DetectorChoice,
    _params: PostprocessParams,
) -> Result<Box<dyn Detector>, VisionError> {
    Err(VisionError::Runtime(
        "this build of crackbot-vision has no ONNX detector (enable its `onnx` feature)".into(),
    ))
}

/// The default model, relative to the repository root: CrackSeg fine-tuned with the
/// DeepCrack and CRACK500 tiles (`models/detector/MODEL_CARD.md`), the one that sees real cracks
/// best; the from-scratch CrackSeg it started from is `models/detector/crack-detector-320.onnx`.
pub const DEFAULT_MODEL: &str = "models/detector/crackseg-tiles/crack-detector-320.onnx";

/// The input sizes of the models trained in `models/detector/` (`crack-detector-<size>.onnx`).
pub const TRAINED_INPUT_SIZES: [usize; 3] = [256, 320, 416];

/// The default model: [`DEFAULT_MODEL`] as [`crackbot_datasets::model_path`] finds it
/// (`$CRACKBOT_MODELS`, beside the binary, the working directory or the repository it was built
/// from).
pub fn default_model() -> PathBuf {
    crackbot_datasets::model_path(DEFAULT_MODEL.trim_start_matches("models/"))
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
        let classical = build_detector(
            &DetectorChoice {
                kind: DetectorKind::Classical,
                ..DetectorChoice::default()
            },
            PostprocessParams::default(),
        )
        .unwrap();
        assert!(
            classical.name().contains("classical"),
            "{}",
            classical.name()
        );
        assert_eq!(
            "classical".parse::<DetectorKind>(),
            Ok(DetectorKind::Classical)
        );
        assert!("yolo".parse::<DetectorKind>().unwrap_err().contains("onnx"));
        let all = trained_models();
        assert_eq!(all.len(), 3);
        assert!(all[1].ends_with("crackseg-tiles/crack-detector-320.onnx"));
    }
}
