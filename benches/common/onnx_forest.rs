//! Any crackbot forest file (classifier or regressor) exported to ONNX by `scripts/forest_to_onnx.sh` and
//! run through ONNX Runtime (`ort`, load-dynamic, the library that `crackbot_vision::onnx` finds), next to
//! the same file loaded by crackbot-forest. Shared, through `#[path]`, by `benches/tactile.rs` and
//! `tests/forest_onnx.rs`.
//!
//! Errors are strings that say what to do (run `bash scripts/setup.sh`, or the exporter's message).
#![allow(
    dead_code,
    reason = "included by several test or bench crates, each using a subset: dead in some, not in others"
)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crackbot_forest::{Classifier, RandomForest, RandomForestRegressor};
use ort::session::Session;
use ort::value::TensorRef;

/// The workspace root (the root package's manifest folder).
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `scripts/forest_to_onnx.sh FOREST ONNX` (which makes its venv on first use).
pub fn export(forest: &Path, onnx: &Path) -> Result<(), String> {
    export_with(forest, onnx, &[])
}

/// Whether `path` is a deployed tactile model (`CRKTACTL`, crates/tactile/src/model.rs), whose forests
/// are sections.
pub fn is_tactile_model(path: &Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok()
        && &magic == b"CRKTACTL"
}

/// Exports section `section` of a deployed tactile model to `onnx`, and writes that forest to
/// `forest_out` as a plain forest file.
pub fn export_section(
    model: &Path,
    section: &str,
    onnx: &Path,
    forest_out: &Path,
) -> Result<(), String> {
    let out = forest_out.to_string_lossy();
    export_with(
        model,
        onnx,
        &["--section", section, "--save-forest", out.as_ref()],
    )
}

/// [`export`] with further arguments for the script.
fn export_with(forest: &Path, onnx: &Path, extra: &[&str]) -> Result<(), String> {
    let script = workspace_root().join("scripts/forest_to_onnx.sh");
    let out = std::process::Command::new("bash")
        .arg(&script)
        .arg(forest)
        .arg(onnx)
        .args(extra)
        .output()
        .map_err(|e| format!("running {}: {e}", script.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} {} {} failed ({}): {}{}\n(the exporter's venv is made by `bash scripts/forest_to_onnx.sh --setup`, \
             which `bash scripts/setup.sh` runs; it needs python3 with venv and pip access once)",
            script.display(),
            forest.display(),
            onnx.display(),
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        ));
    }
    Ok(())
}

/// The process-wide ONNX Runtime environment (the library is loaded once per process).
fn environment() -> Result<&'static ort::environment::Environment, String> {
    static ENV: OnceLock<Result<ort::environment::Environment, String>> = OnceLock::new();
    ENV.get_or_init(|| {
        let path = crackbot_vision::onnx::runtime_library().map_err(|e| e.to_string())?;
        ort::init_from(&path)
            .map_err(|e| format!("loading ONNX Runtime from {}: {e}", path.display()))?
            .with_name("crackbot-forest-onnx")
            .build()
            .map_err(|e| format!("starting ONNX Runtime from {}: {e}", path.display()))
    })
    .as_ref()
    .map_err(Clone::clone)
}

/// A forest file loaded by crackbot-forest, whichever its kind.
pub enum Ours {
    /// A classifier (`predict` = class index, probabilities = mean leaf probabilities).
    Classifier(RandomForest),
    /// A regressor (`predict` = mean of the leaf means).
    Regressor(RandomForestRegressor),
}

impl Ours {
    /// Loads a forest file of either kind (the kind is read from the header, then the whole file is
    /// checked by crackbot-forest).
    pub fn load(path: &Path) -> Result<Self, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let kind = bytes
            .get(12..16)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        let err = |e: crackbot_forest::ForestError| format!("{}: {e}", path.display());
        match kind {
            Some(2) => Ok(Ours::Regressor(
                RandomForestRegressor::from_bytes(&bytes).map_err(err)?,
            )),
            _ => Ok(Ours::Classifier(
                RandomForest::from_bytes(&bytes).map_err(err)?,
            )),
        }
    }

    /// Features per row.
    pub fn n_features(&self) -> usize {
        match self {
            Ours::Classifier(f) => Classifier::n_features(f),
            Ours::Regressor(f) => f.n_features(),
        }
    }

    /// Values per row of [`OrtForest::run`]'s `values`: classes, or 1.
    pub fn width(&self) -> usize {
        match self {
            Ours::Classifier(f) => f.n_classes(),
            Ours::Regressor(_) => 1,
        }
    }

    /// Kind, trees and nodes, for printing.
    pub fn describe(&self) -> String {
        match self {
            Ours::Classifier(f) => format!(
                "classifier, {} classes, {} trees, {} nodes, depth {}",
                f.n_classes(),
                f.n_trees(),
                f.n_nodes(),
                f.max_depth()
            ),
            Ours::Regressor(f) => {
                format!("regressor, {} trees, {} nodes", f.n_trees(), f.n_nodes())
            }
        }
    }

    /// Class probabilities (classifier) or predictions (regressor) of every row of `x`, row-major.
    pub fn values(&self, x: &[f32]) -> Vec<f32> {
        let nf = self.n_features();
        let rows = x.len() / nf;
        let mut out = vec![0f32; rows * self.width()];
        match self {
            Ours::Classifier(f) => f.predict_proba_batch(x, nf, &mut out),
            Ours::Regressor(f) => f.predict_batch(x, nf, &mut out),
        }
        .expect("rows of the model's width");
        out
    }

    /// The class index of every row (classifier), empty for a regressor.
    pub fn classes(&self, x: &[f32]) -> Vec<u32> {
        match self {
            Ours::Classifier(f) => {
                let nf = Classifier::n_features(f);
                let mut out = vec![0u32; x.len() / nf];
                f.predict_batch(x, nf, &mut out)
                    .expect("rows of the model's width");
                out
            }
            Ours::Regressor(_) => Vec::new(),
        }
    }
}

/// An exported forest in an ONNX Runtime session.
pub struct OrtForest {
    session: Session,
    n_features: usize,
    classifier: bool,
}

/// What [`OrtForest::run`] returns.
pub struct OrtOutput {
    /// `label` (class index per row), classifiers only.
    pub labels: Vec<i64>,
    /// `probabilities` (`[rows, classes]`) or `variable` (`[rows, 1]`), row-major.
    pub values: Vec<f32>,
}

impl OrtForest {
    /// Loads the ONNX file written by [`export`] for a forest of `n_features` features, on `threads`
    /// intra-op threads (and one inter-op thread).
    pub fn load(onnx: &Path, n_features: usize, threads: usize) -> Result<Self, String> {
        let env = environment()?;
        let fail = |e: &dyn std::fmt::Display| format!("{}: {e}", onnx.display());
        let session = Session::builder(env)
            .map_err(|e| fail(&e))?
            .with_intra_threads(threads.max(1))
            .map_err(|e| fail(&e))?
            .with_inter_threads(1)
            .map_err(|e| fail(&e))?
            .commit_from_file(onnx)
            .map_err(|e| fail(&e))?;
        let outputs: Vec<String> = session
            .outputs()
            .iter()
            .map(|o| o.name().to_string())
            .collect();
        let classifier = match outputs.iter().map(String::as_str).collect::<Vec<_>>()[..] {
            ["label", "probabilities"] => true,
            ["variable"] => false,
            _ => return Err(fail(&format!("unexpected outputs {outputs:?}"))),
        };
        Ok(Self {
            session,
            n_features,
            classifier,
        })
    }

    /// Runs the rows of `x` (row-major, `n_features` per row).
    pub fn run(&mut self, x: &[f32]) -> Result<OrtOutput, String> {
        let rows = x.len() / self.n_features;
        let input =
            TensorRef::from_array_view(([rows, self.n_features], x)).map_err(|e| e.to_string())?;
        let out = self
            .session
            .run(ort::inputs!["x" => input])
            .map_err(|e| e.to_string())?;
        if self.classifier {
            let (_, labels) = out["label"]
                .try_extract_tensor::<i64>()
                .map_err(|e| e.to_string())?;
            let (_, values) = out["probabilities"]
                .try_extract_tensor::<f32>()
                .map_err(|e| e.to_string())?;
            Ok(OrtOutput {
                labels: labels.to_vec(),
                values: values.to_vec(),
            })
        } else {
            let (_, values) = out["variable"]
                .try_extract_tensor::<f32>()
                .map_err(|e| e.to_string())?;
            Ok(OrtOutput {
                labels: Vec::new(),
                values: values.to_vec(),
            })
        }
    }

    /// Runs one row and returns the first output value (class index, or the regression value): the
    /// per-window call the latency bench times (outputs read, not copied).
    pub fn run_one(&mut self, row: &[f32]) -> f32 {
        let input = TensorRef::from_array_view(([1usize, self.n_features], row)).expect("input");
        let out = self
            .session
            .run(ort::inputs!["x" => input])
            .expect("ONNX Runtime run");
        if self.classifier {
            out["label"].try_extract_tensor::<i64>().expect("label").1[0] as f32
        } else {
            out["variable"]
                .try_extract_tensor::<f32>()
                .expect("variable")
                .1[0]
        }
    }
}

/// The feature rows of a windows CSV (a header line, then one window per line; the first
/// `n_features` columns are the model's features in order, further columns such as `class` are
/// ignored), row-major.
pub fn read_windows_csv(path: &Path, n_features: usize) -> Result<Vec<f32>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut x = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() < n_features {
            return Err(format!(
                "{}:{}: {} columns, the model has {n_features} features",
                path.display(),
                i + 1,
                cols.len()
            ));
        }
        for c in &cols[..n_features] {
            x.push(
                c.trim()
                    .parse::<f32>()
                    .map_err(|e| format!("{}:{}: {c:?}: {e}", path.display(), i + 1))?,
            );
        }
    }
    if x.is_empty() {
        return Err(format!("{}: no windows", path.display()));
    }
    Ok(x)
}

/// How ONNX Runtime's output differs from ours on the rows of `x`: the largest absolute difference of
/// the values (probabilities or predictions, relative to max(1, |ours|) for a regressor), and the rows
/// whose class differs (classifiers).
pub struct Agreement {
    /// Rows compared.
    pub rows: usize,
    /// Largest difference of the values.
    pub max_diff: f32,
    /// Rows where ONNX Runtime's `label` is not our class.
    pub class_differs: Vec<usize>,
}

/// Compares ours and ONNX Runtime's batch outputs on the rows of `x`.
pub fn compare(ours: &Ours, onnx: &mut OrtForest, x: &[f32]) -> Result<Agreement, String> {
    let theirs = onnx.run(x)?;
    let mine = ours.values(x);
    if theirs.values.len() != mine.len() {
        return Err(format!(
            "ONNX Runtime gave {} values, ours {}",
            theirs.values.len(),
            mine.len()
        ));
    }
    let regressor = matches!(ours, Ours::Regressor(_));
    let max_diff = mine
        .iter()
        .zip(&theirs.values)
        .map(|(&a, &b)| {
            let d = (a - b).abs();
            if regressor {
                d / a.abs().max(1.0)
            } else {
                d
            }
        })
        .fold(0f32, f32::max);
    let classes = ours.classes(x);
    let class_differs = classes
        .iter()
        .zip(&theirs.labels)
        .enumerate()
        .filter(|(_, (&a, &b))| i64::from(a) != b)
        .map(|(i, _)| i)
        .collect();
    Ok(Agreement {
        rows: x.len() / ours.n_features(),
        max_diff,
        class_differs,
    })
}
