//! The authors' real surface-type recordings as the paper's MAV D1D2+P windows (train on repetition 1,
//! test on repetition 2). Shared, through `#[path]`, by `benches/tactile.rs`,
//! `tests/linfa_flat_conversion.rs` and the examples `export_windows` and `per_window_instructions` of
//! crackbot-research, so every benchmark sees the same windows.
#![allow(
    dead_code,
    reason = "included by several test or bench crates, each using a subset: dead in some, not in others"
)]

use std::path::{Path, PathBuf};

use crackbot_recording::collect_recordings;
use crackbot_tactile::dataset::{build_windows, detect_experiment, PipelineConfig, WindowSet};

/// The authors' surface-type recordings (4 classes, repetitions 1–3): `../shared/data/tactile/type`, or a
/// clear stop naming the missing folder (see `crackbot-datasets`).
pub fn data_dir() -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::TACTILE_TYPE)
}

/// The paper's pipeline: eq. 2 segmentation, 10-sample windows every 2 samples, MAV of D1, D2, P.
pub fn config() -> PipelineConfig {
    PipelineConfig::default()
}

/// Real windows and samples of the surface-type experiment.
pub struct Real {
    /// Windows of repetition 1 (training).
    pub train: WindowSet,
    /// Windows of repetition 2 (prediction).
    pub test: WindowSet,
    /// Every sample `[D1, D2, D3, P]` of repetition 2's slides, in recording order (for the streaming path).
    pub test_samples: Vec<[f64; 4]>,
}

/// Loads repetitions 1 and 2 of the surface-type recordings in `dir` (`shared/data/tactile/type`) and builds
/// their windows.
pub fn load(dir: &Path) -> Real {
    let recordings = collect_recordings(&[dir.to_path_buf()]).expect("the authors' recordings");
    let experiment = detect_experiment(&recordings).expect("experiment");
    let rep = |r: u32| -> Vec<_> {
        recordings
            .iter()
            .filter(|(_, rec)| rec.repetition() == Some(r))
            .cloned()
            .collect()
    };
    let (rep1, rep2) = (rep(1), rep(2));
    assert!(
        !rep1.is_empty() && !rep2.is_empty(),
        "repetitions 1 and 2 in {}",
        dir.display()
    );
    let cfg = config();
    let train = build_windows(&rep1, experiment, &cfg).expect("windows of repetition 1");
    let test = build_windows(&rep2, experiment, &cfg).expect("windows of repetition 2");
    let test_samples = rep2
        .iter()
        .flat_map(|(_, rec)| rec.rows.iter().map(crackbot_recording::Row::channels))
        .collect();
    Real {
        train,
        test,
        test_samples,
    }
}
