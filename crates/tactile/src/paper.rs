//! The paper's evaluation grid, with its intersession protocol: for every feature (RAW, MAV, RMS)
//! × channel set (P, D1D2D3, D1D2D3+P, D1D2+P) × classifier (RF, KNN, QDA), train on the
//! recordings of one repetition and test on each other repetition, one at a time. With
//! repetitions 1–3 that gives 3 × 2 = 6 results per cell (the paper had 5 × 4 = 20).
//!
//! Every test repetition is one the model never saw: the leaky 70/30 split of overlapping windows
//! is not offered.
//!
//! [`paper_study`] is the whole `crackbot tactile paper` run: every folder's grid, Markdown and JSON.

use std::path::{Path, PathBuf};

use crackbot_dsp::{Feature, FeatureSet, FeatureSpec};
use crackbot_recording::{collect_recordings, Recording};
use serde::Serialize;

use crate::dataset::{detect_experiment, Experiment, PipelineConfig, WindowSet};
use crate::error::check_n_trees;
use crate::eval::{test_classifier, train_classifier, ClassifierKind};
use crate::metrics::ConfusionMatrix;
use crate::stats::{kruskal_wallis, mean_std, KruskalWallis};
use crate::TactileError;

/// One train-repetition → test-repetition result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairResult {
    /// Repetition trained on.
    pub train_repetition: u32,
    /// Repetition tested on.
    pub test_repetition: u32,
    /// Window-level accuracy.
    pub window_accuracy: f64,
    /// Window-level weighted precision.
    pub window_precision: f64,
    /// Window-level weighted recall.
    pub window_recall: f64,
    /// Slide-level accuracy.
    pub slide_accuracy: f64,
}

/// All results of one cell of the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CellResult {
    /// Classifier name.
    pub classifier: String,
    /// Feature name.
    pub feature: String,
    /// Channel-set name.
    pub set: String,
    /// One entry per (train, test) pair.
    pub pairs: Vec<PairResult>,
    /// Mean window accuracy over the pairs.
    pub accuracy_mean: f64,
    /// Standard deviation of the window accuracy over the pairs.
    pub accuracy_std: f64,
    /// Mean weighted precision.
    pub precision_mean: f64,
    /// Mean weighted recall.
    pub recall_mean: f64,
    /// Mean slide accuracy.
    pub slide_accuracy_mean: f64,
    /// Window confusion matrix summed over the pairs.
    pub confusion: ConfusionMatrix,
}

/// The whole grid for one experiment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PaperTables {
    /// The experiment.
    pub experiment: Experiment,
    /// Class names.
    pub classes: Vec<String>,
    /// Repetitions found.
    pub repetitions: Vec<u32>,
    /// One entry per classifier × feature × set.
    pub cells: Vec<CellResult>,
    /// Kruskal–Wallis across the channel sets, per classifier and feature (groups: the pair
    /// accuracies of each set).
    pub kruskal_wallis_sets: Vec<(String, String, Option<KruskalWallis>)>,
}

/// Recordings grouped by repetition number: `(repetition, [(path, recording)])`.
pub type Repetitions = Vec<(u32, Vec<(PathBuf, Recording)>)>;

/// Splits recordings by repetition number (column 9), sorted.
pub fn by_repetition(recordings: Vec<(PathBuf, Recording)>) -> Result<Repetitions, TactileError> {
    let mut groups: Repetitions = Vec::new();
    for (path, rec) in recordings {
        let r = rec
            .repetition()
            .ok_or_else(|| TactileError::MixedRepetitions { path: path.clone() })?;
        match groups.iter_mut().find(|(k, _)| *k == r) {
            Some((_, v)) => v.push((path, rec)),
            None => groups.push((r, vec![(path, rec)])),
        }
    }
    groups.sort_by_key(|(k, _)| *k);
    if groups.len() < 2 {
        return Err(TactileError::TooFewRepetitions {
            found: groups.iter().map(|(k, _)| *k).collect(),
        });
    }
    Ok(groups)
}

/// Runs the grid. `base` gives the segmentation, window and normalisation; its feature spec is
/// replaced cell by cell. `progress` is called with a line per finished cell.
pub fn run_grid(
    experiment: Experiment,
    repetitions: &[(u32, Vec<(PathBuf, Recording)>)],
    classifiers: &[ClassifierKind],
    base: &PipelineConfig,
    seed: u64,
    mut progress: impl FnMut(&CellResult),
) -> Result<PaperTables, TactileError> {
    let mut cells = Vec::new();
    for &feature in &Feature::ALL {
        for &set in &FeatureSet::ALL {
            let config = PipelineConfig {
                spec: FeatureSpec::new(feature, set),
                ..base.clone()
            };
            let pipeline = config.check()?;
            let sets: Vec<(u32, WindowSet)> = repetitions
                .iter()
                .map(|(r, recs)| pipeline.build_windows(recs, experiment).map(|w| (*r, w)))
                .collect::<Result<_, _>>()?;
            for &kind in classifiers {
                let mut pairs = Vec::new();
                let mut confusion = ConfusionMatrix::new(experiment.n_classes());
                for (train_rep, train) in &sets {
                    let model = train_classifier(train, kind, seed)?;
                    for (test_rep, test) in sets.iter().filter(|(r, _)| r != train_rep) {
                        let o = test_classifier(model.as_ref(), test)?;
                        confusion.merge(&o.windows)?;
                        pairs.push(PairResult {
                            train_repetition: *train_rep,
                            test_repetition: *test_rep,
                            window_accuracy: o.windows.accuracy(),
                            window_precision: o.windows.weighted_precision(),
                            window_recall: o.windows.weighted_recall(),
                            slide_accuracy: o.slides.accuracy(),
                        });
                    }
                }
                let acc: Vec<f64> = pairs.iter().map(|p| p.window_accuracy).collect();
                let (accuracy_mean, accuracy_std) = mean_std(&acc);
                let mean = |f: fn(&PairResult) -> f64| {
                    mean_std(&pairs.iter().map(f).collect::<Vec<_>>()).0
                };
                let cell = CellResult {
                    classifier: kind.name().to_string(),
                    feature: feature.name().to_string(),
                    set: set.name().to_string(),
                    accuracy_mean,
                    accuracy_std,
                    precision_mean: mean(|p| p.window_precision),
                    recall_mean: mean(|p| p.window_recall),
                    slide_accuracy_mean: mean(|p| p.slide_accuracy),
                    pairs,
                    confusion,
                };
                progress(&cell);
                cells.push(cell);
            }
        }
    }
    let mut kruskal_wallis_sets = Vec::new();
    for kind in classifiers {
        for feature in Feature::ALL {
            let groups: Vec<Vec<f64>> = cells
                .iter()
                .filter(|c| c.classifier == kind.name() && c.feature == feature.name())
                .map(|c| c.pairs.iter().map(|p| p.window_accuracy).collect())
                .collect();
            let refs: Vec<&[f64]> = groups.iter().map(Vec::as_slice).collect();
            kruskal_wallis_sets.push((
                kind.name().to_string(),
                feature.name().to_string(),
                kruskal_wallis(&refs).ok(),
            ));
        }
    }
    Ok(PaperTables {
        experiment,
        classes: experiment
            .class_names()
            .iter()
            .map(std::string::ToString::to_string)
            .collect(),
        repetitions: repetitions.iter().map(|(r, _)| *r).collect(),
        cells,
        kruskal_wallis_sets,
    })
}

/// The paper's figures for its Table 1 (recognition) and Table 2 (width), random forest, in %:
/// (feature, set, mean accuracy). The paper's sets are named P, D1D2D3, D1D2D3+P, D1D2+P here.
pub fn paper_reference(experiment: Experiment) -> &'static [(&'static str, &'static str, f64)] {
    match experiment {
        Experiment::Recognition => &[
            ("RAW", "P", 81.86),
            ("MAV", "P", 77.70),
            ("RMS", "P", 77.17),
            ("RAW", "D1D2D3", 80.16),
            ("MAV", "D1D2D3", 88.27),
            ("RMS", "D1D2D3", 87.96),
            ("RAW", "D1D2D3+P", 92.75),
            ("MAV", "D1D2D3+P", 94.64),
            ("RMS", "D1D2D3+P", 94.48),
            ("RAW", "D1D2+P", 91.88),
            ("MAV", "D1D2+P", 95.17),
            ("RMS", "D1D2+P", 94.90),
        ],
        Experiment::Width => &[
            ("RAW", "P", 63.09),
            ("MAV", "P", 61.54),
            ("RMS", "P", 60.11),
            ("RAW", "D1D2D3", 48.33),
            ("MAV", "D1D2D3", 58.02),
            ("RMS", "D1D2D3", 58.13),
            ("RAW", "D1D2D3+P", 73.97),
            ("MAV", "D1D2D3+P", 79.81),
            ("RMS", "D1D2D3+P", 79.55),
            ("RAW", "D1D2+P", 72.73),
            ("MAV", "D1D2+P", 80.29),
            ("RMS", "D1D2+P", 80.34),
        ],
    }
}

impl PaperTables {
    /// The tables as Markdown: per classifier, the paper's columns, plus the paper's own RF
    /// figure beside ours and the slide-level accuracy.
    pub fn to_markdown(&self) -> String {
        let mut md = format!(
            "## {} experiment — intersession (train on one repetition, test on each other one; repetitions {:?})\n\n",
            self.experiment.name(),
            self.repetitions
        );
        let reference = paper_reference(self.experiment);
        let mut classifiers: Vec<&str> = Vec::new();
        for c in &self.cells {
            if !classifiers.contains(&c.classifier.as_str()) {
                classifiers.push(&c.classifier);
            }
        }
        for clf in classifiers {
            md.push_str(&format!("### {clf}\n\n| feature | mean (%) | std | precision (%) | recall (%) | slide accuracy (%) | paper RF mean (%) |\n|---|---|---|---|---|---|---|\n"));
            for c in self.cells.iter().filter(|c| c.classifier == clf) {
                let paper = reference
                    .iter()
                    .find(|(f, s, _)| *f == c.feature && *s == c.set)
                    .map_or("–".to_string(), |(_, _, v)| format!("{v:.2}"));
                md.push_str(&format!(
                    "| {} — {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} |\n",
                    c.feature,
                    c.set,
                    100.0 * c.accuracy_mean,
                    100.0 * c.accuracy_std,
                    100.0 * c.precision_mean,
                    100.0 * c.recall_mean,
                    100.0 * c.slide_accuracy_mean,
                    paper
                ));
            }
            md.push('\n');
        }
        md.push_str("### Kruskal–Wallis across channel sets (window accuracies of the pairs)\n\n| classifier | feature | H | p |\n|---|---|---|---|\n");
        for (clf, feature, kw) in &self.kruskal_wallis_sets {
            match kw {
                Some(k) => md.push_str(&format!(
                    "| {clf} | {feature} | {:.3} | {:.3e} |\n",
                    k.h, k.p
                )),
                None => md.push_str(&format!("| {clf} | {feature} | – | – |\n")),
            }
        }
        md
    }
}

/// What [`paper_study`] runs.
#[derive(Debug, Clone, PartialEq)]
pub struct PaperConfig {
    /// The classifiers of the grid.
    pub classifiers: Vec<ClassifierKind>,
    /// Trees of the random forests (the command line builds [`ClassifierKind::Forest`] with it); at
    /// least 1.
    pub n_trees: usize,
    /// Segmentation, windows and normalisation; the feature spec is replaced cell by cell.
    pub base: PipelineConfig,
    /// Seed of the forests.
    pub seed: u64,
}

impl PaperConfig {
    /// Checks the number of trees (`--trees must be at least 1`); [`paper_study`] does too.
    pub fn validate(&self) -> Result<(), TactileError> {
        check_n_trees(self.n_trees)
    }
}

/// Progress of [`paper_study`].
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub enum PaperEvent<'a> {
    /// The grid of one folder starts.
    Folder {
        /// The folder (or file) of recordings.
        folder: &'a Path,
        /// Its experiment.
        experiment: Experiment,
        /// Cells of its grid.
        cells: usize,
    },
    /// One cell of the grid is done.
    Cell {
        /// The experiment of the folder.
        experiment: Experiment,
        /// The cell.
        cell: &'a CellResult,
    },
    /// The grid of one folder is done (its figures and tables follow).
    FolderDone {
        /// The folder.
        folder: &'a Path,
    },
}

/// What [`paper_study`] wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PaperReport {
    /// The tables of every folder, as Markdown with the figures' links.
    pub markdown: String,
    /// The tables of every folder (the JSON file holds this list).
    pub tables: Vec<PaperTables>,
    /// `paper-tables.md`.
    pub markdown_path: PathBuf,
    /// `paper-tables.json`.
    pub json_path: PathBuf,
}

/// The paper's tables for every folder of `data` (one experiment per folder): reads the recordings,
/// detects the experiment, groups by repetition and runs the grid ([`run_grid`]), then writes
/// `paper-tables.md` and `paper-tables.json` into `out` (created). `figures(out, tables)` draws the
/// folder's figures into `out` and returns their Markdown (or nothing); `progress` follows the grid.
pub fn paper_study(
    config: &PaperConfig,
    data: &[PathBuf],
    out: &Path,
    mut progress: impl FnMut(PaperEvent<'_>),
    mut figures: impl FnMut(&Path, &PaperTables) -> Result<String, TactileError>,
) -> Result<PaperReport, TactileError> {
    config.validate()?;
    std::fs::create_dir_all(out).map_err(TactileError::creating(out))?;
    let mut markdown =
        String::from("# The paper's tables, reproduced by `crackbot tactile paper`\n\n");
    let mut all = Vec::new();
    for folder in data {
        let recordings = collect_recordings(std::slice::from_ref(folder))?;
        let experiment = detect_experiment(&recordings)?;
        let repetitions = by_repetition(recordings)?;
        progress(PaperEvent::Folder {
            folder,
            experiment,
            cells: Feature::ALL.len() * FeatureSet::ALL.len() * config.classifiers.len(),
        });
        let tables = run_grid(
            experiment,
            &repetitions,
            &config.classifiers,
            &config.base,
            config.seed,
            |cell| progress(PaperEvent::Cell { experiment, cell }),
        )?;
        progress(PaperEvent::FolderDone { folder });
        markdown.push_str(&format!("Data: {}\n\n", folder.display()));
        markdown.push_str(&tables.to_markdown());
        markdown.push('\n');
        markdown.push_str(&figures(out, &tables)?);
        all.push(tables);
    }
    let markdown_path = out.join("paper-tables.md");
    let json_path = out.join("paper-tables.json");
    std::fs::write(&markdown_path, &markdown).map_err(TactileError::writing(&markdown_path))?;
    std::fs::write(&json_path, serde_json::to_string_pretty(&all)?)
        .map_err(TactileError::writing(&json_path))?;
    Ok(PaperReport {
        markdown,
        tables: all,
        markdown_path,
        json_path,
    })
}
