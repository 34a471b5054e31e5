//! Walking the saved fused trials of `crackbot-lab mission trials --out DIR` (shared by the
//! examples that replay them).

use std::path::{Path, PathBuf};

use serde_json::Value;

/// One saved fused trial: its folder, its seed (from the folder's name, `?` where it has
/// none) and its `report.json`.
pub struct SavedTrial {
    pub folder: PathBuf,
    pub seed: String,
    pub report: Value,
}

/// The fused trials under `dir` (`trial-SEED-fused`), in order of their names.
pub fn fused_trials(dir: &Path) -> Result<Vec<SavedTrial>, Box<dyn std::error::Error>> {
    let mut folders: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.to_string_lossy().ends_with("-fused"))
        .collect();
    folders.sort();
    folders
        .into_iter()
        .map(|folder| {
            let path = folder.join("report.json");
            let text =
                std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
            let report: Value =
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
            let seed = folder
                .file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.split('-').nth(1))
                .unwrap_or("?")
                .to_string();
            Ok(SavedTrial {
                folder,
                seed,
                report,
            })
        })
        .collect()
}
