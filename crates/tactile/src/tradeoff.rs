//! Error against run time for the random forest: for a grid of tree counts × depth limits, train on
//! one [`WindowSet`], test on another, and record the window and slide accuracy, the model size,
//! the training time and the median single-window prediction latency on one thread.
//!
//! Latency is what the robot pays per window when it classifies windows one at a time as they
//! arrive: [`Classifier::predict`] on one row, on the calling thread. Timing one call would be
//! dominated by the timer, so the test windows are taken in order in batches (1000 by default),
//! each batch is timed as a whole and divided by its length, and the median over the batches is
//! reported. Consecutive windows overlap, like the stream the robot sees, so their paths through
//! the trees are similar; a shuffled order would be slower on large forests.
//!
//! [`tradeoff_study`] is the whole `crackbot tactile tradeoff` run: recordings to Markdown and JSON.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crackbot_forest::{Classifier, Dataset, ForestParams, RandomForest};
use crackbot_recording::collect_recordings;
use serde::Serialize;

use crate::dataset::{choose_experiment, Experiment, PipelineConfig, WindowSet};
use crate::eval::test_classifier;
use crate::TactileError;

/// The grid and the measurement settings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffConfig {
    /// Tree counts to try.
    pub n_trees: Vec<usize>,
    /// Depth limits to try (`None`: fully grown trees).
    pub max_depths: Vec<Option<usize>>,
    /// Seed of the forests. Tree `i` depends on `(seed, i)` only, so a forest of `n` trees holds
    /// the trees of every smaller forest of the same depth limit.
    pub seed: u64,
    /// Windows per timed batch.
    pub latency_batch: usize,
}

impl TradeoffConfig {
    /// Checks the grid and the batch ([`run_tradeoff`] does too): at least one tree count and one
    /// depth limit, all of them at least 1, and a batch of at least one window.
    pub fn validate(&self) -> Result<(), TactileError> {
        if self.n_trees.is_empty() || self.max_depths.is_empty() {
            return Err(TactileError::InvalidSetting {
                reason: "the grid needs at least one tree count and one depth limit",
            });
        }
        if self.n_trees.contains(&0) {
            return Err(TactileError::ListTooSmall {
                argument: "--trees",
                what: "tree count",
                min: 1,
            });
        }
        if self.latency_batch == 0 {
            return Err(TactileError::TooSmall {
                argument: "--batch",
                min: 1,
            });
        }
        if self.max_depths.contains(&Some(0)) {
            return Err(TactileError::InvalidSetting {
                reason: "tree counts and depth limits must be at least 1",
            });
        }
        Ok(())
    }
}

impl Default for TradeoffConfig {
    /// Trees 1, 2, 5, 10, 20, 50, 100, 200; depth unlimited, 20, 12, 8; seed 1; batches of 1000.
    fn default() -> Self {
        TradeoffConfig {
            n_trees: vec![1, 2, 5, 10, 20, 50, 100, 200],
            max_depths: vec![None, Some(20), Some(12), Some(8)],
            seed: 1,
            latency_batch: 1000,
        }
    }
}

/// One forest of the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffRow {
    /// Number of trees.
    pub n_trees: usize,
    /// Depth limit (`None`: unlimited).
    pub max_depth: Option<usize>,
    /// Depth of the deepest leaf actually grown.
    pub depth_reached: usize,
    /// Total number of nodes of the forest.
    pub n_nodes: usize,
    /// Size of the serialised model, bytes.
    pub model_bytes: usize,
    /// Training time, seconds (rayon's threads, see [`Tradeoff::train_threads`]).
    pub train_seconds: f64,
    /// Median single-window prediction time on one thread, seconds.
    pub latency_seconds: f64,
    /// Window-level accuracy on the test set.
    pub window_accuracy: f64,
    /// Slide-level accuracy on the test set (mean probability over a slide's windows).
    pub slide_accuracy: f64,
}

/// The measured grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tradeoff {
    /// Experiment of the windows.
    pub experiment: Experiment,
    /// Training windows.
    pub train_windows: usize,
    /// Test windows.
    pub test_windows: usize,
    /// Test slides (with at least one window).
    pub test_slides: usize,
    /// Features per window.
    pub n_features: usize,
    /// Threads that trained the forests (rayon's global pool).
    pub train_threads: usize,
    /// The settings.
    pub config: TradeoffConfig,
    /// One row per depth limit × tree count, in the order of the configuration (depth outer).
    pub rows: Vec<TradeoffRow>,
}

/// Median over batches of the single-row [`Classifier::predict`] time of `model` on the windows of
/// `test`, taken in order, `batch` windows per timed batch, on the calling thread; seconds per
/// window. A first pass over one batch warms the caches and is not counted.
pub fn median_latency(
    model: &(dyn Classifier + Send + Sync),
    test: &WindowSet,
    batch: usize,
) -> Result<f64, TactileError> {
    let n = test.n_rows();
    if n == 0 || batch == 0 {
        return Err(TactileError::InvalidSetting {
            reason: "latency needs at least one test window and a batch of at least one",
        });
    }
    let time_batch = |start: usize, end: usize| {
        let t = Instant::now();
        let mut acc = 0u32;
        for i in start..end {
            acc = acc.wrapping_add(model.predict(black_box(test.row(i))));
        }
        black_box(acc);
        t.elapsed().as_secs_f64() / (end - start) as f64
    };
    time_batch(0, batch.min(n));
    let mut per_window: Vec<f64> = (0..n)
        .step_by(batch)
        .map(|start| time_batch(start, (start + batch).min(n)))
        .collect();
    per_window.sort_by(f64::total_cmp);
    let mid = per_window.len() / 2;
    Ok(if per_window.len() % 2 == 1 {
        per_window[mid]
    } else {
        (per_window[mid - 1] + per_window[mid]) / 2.0
    })
}

/// Runs the grid ([`TradeoffConfig::validate`] first): trains on `train`, tests on `test`.
/// `progress` is called after each forest.
pub fn run_tradeoff(
    train: &WindowSet,
    test: &WindowSet,
    config: &TradeoffConfig,
    mut progress: impl FnMut(&TradeoffRow),
) -> Result<Tradeoff, TactileError> {
    config.validate()?;
    if train.experiment != test.experiment || train.n_features != test.n_features {
        return Err(TactileError::WindowSetMismatch {
            train_experiment: train.experiment,
            train_features: train.n_features,
            test_experiment: test.experiment,
            test_features: test.n_features,
        });
    }
    let data = Dataset::with_classes(
        train.x.clone(),
        train.n_features,
        train.y.clone(),
        train.experiment.n_classes(),
    )?;
    let mut rows = Vec::new();
    for &max_depth in &config.max_depths {
        for &n_trees in &config.n_trees {
            let params = ForestParams::classifier()
                .n_trees(n_trees)
                .max_depth(max_depth)
                .seed(config.seed);
            let started = Instant::now();
            let forest = RandomForest::fit(&data, &params)?;
            let train_seconds = started.elapsed().as_secs_f64();
            let outcome = test_classifier(&forest, test)?;
            let latency_seconds = median_latency(&forest, test, config.latency_batch)?;
            let row = TradeoffRow {
                n_trees,
                max_depth,
                depth_reached: forest.max_depth(),
                n_nodes: forest.n_nodes(),
                model_bytes: forest.to_bytes().len(),
                train_seconds,
                latency_seconds,
                window_accuracy: outcome.windows.accuracy(),
                slide_accuracy: outcome.slides.accuracy(),
            };
            progress(&row);
            rows.push(row);
        }
    }
    Ok(Tradeoff {
        experiment: train.experiment,
        train_windows: train.n_rows(),
        test_windows: test.n_rows(),
        test_slides: test.slides.iter().filter(|s| !s.windows.is_empty()).count(),
        n_features: train.n_features,
        train_threads: rayon::current_num_threads(),
        config: config.clone(),
        rows,
    })
}

/// `"none"` or the depth limit.
pub fn depth_name(max_depth: Option<usize>) -> String {
    max_depth.map_or_else(|| "none".to_string(), |d| d.to_string())
}

impl Tradeoff {
    /// The table as Markdown, one row per forest, with a line on the data and the measurement.
    pub fn to_markdown(&self) -> String {
        let mut md = format!(
            "{} experiment: trained on {} windows, tested on {} windows ({} slides), {} features per window. \
             Training on {} threads; latency = median over batches of {} consecutive test windows of the \
             single-window `predict` time, one thread.\n\n",
            self.experiment.name(),
            self.train_windows,
            self.test_windows,
            self.test_slides,
            self.n_features,
            self.train_threads,
            self.config.latency_batch
        );
        md.push_str(
            "| max depth | trees | depth reached | nodes | model (KiB) | training (s) | latency (µs/window) | window accuracy (%) | slide accuracy (%) |\n\
             |---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {:.1} | {:.3} | {:.2} | {:.2} | {:.2} |\n",
                depth_name(r.max_depth),
                r.n_trees,
                r.depth_reached,
                r.n_nodes,
                r.model_bytes as f64 / 1024.0,
                r.train_seconds,
                1e6 * r.latency_seconds,
                100.0 * r.window_accuracy,
                100.0 * r.slide_accuracy
            ));
        }
        md
    }
}

/// What [`tradeoff_study`] runs: the recordings, the window pipeline and the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct TradeoffStudy {
    /// Training recordings (files or folders).
    pub train: Vec<PathBuf>,
    /// Test recordings (files or folders).
    pub test: Vec<PathBuf>,
    /// The experiment; `None` detects it from the labels of all recordings.
    pub experiment: Option<Experiment>,
    /// The window pipeline.
    pub pipeline: PipelineConfig,
    /// The grid and the measurement settings.
    pub grid: TradeoffConfig,
}

/// What [`tradeoff_study`] measured and wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TradeoffReport {
    /// The measured grid (the JSON file holds it).
    pub tradeoff: Tradeoff,
    /// The Markdown page (table, data, link to the figure).
    pub markdown: String,
    /// `tradeoff.md`.
    pub markdown_path: PathBuf,
    /// `tradeoff.json`.
    pub json_path: PathBuf,
    /// `tradeoff.png`, drawn by the caller's `figure`.
    pub png_path: PathBuf,
}

/// The whole `crackbot tactile tradeoff` run: reads the recordings, builds their windows, runs the
/// grid ([`run_tradeoff`], `progress` after each forest), creates `out`, lets `figure(png_path,
/// tradeoff)` draw `out/tradeoff.png`, and writes `tradeoff.md` (which links the figure) and
/// `tradeoff.json`. The grid is checked by [`run_tradeoff`]; call [`TradeoffConfig::validate`]
/// first to refuse a bad one before the recordings are read.
pub fn tradeoff_study(
    study: &TradeoffStudy,
    out: &Path,
    progress: impl FnMut(&TradeoffRow),
    figure: impl FnOnce(&Path, &Tradeoff) -> Result<(), TactileError>,
) -> Result<TradeoffReport, TactileError> {
    let grid = &study.grid;
    let train = collect_recordings(&study.train)?;
    let test = collect_recordings(&study.test)?;
    let experiment = choose_experiment(study.experiment, &train, &test)?;
    let pipeline = study.pipeline.check()?;
    let train_set = pipeline.build_windows(&train, experiment)?;
    let test_set = pipeline.build_windows(&test, experiment)?;
    let tradeoff = run_tradeoff(&train_set, &test_set, grid, progress)?;
    std::fs::create_dir_all(out).map_err(TactileError::creating(out))?;
    let png_path = out.join("tradeoff.png");
    figure(&png_path, &tradeoff)?;
    let files = |paths: &[PathBuf]| {
        paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let spec = &study.pipeline.spec;
    let markdown = format!(
        "# Random forest: accuracy against run time (`crackbot tactile tradeoff`)\n\n\
         {} on {} {}, segmentation {}; trained on {} ({} recordings), tested on {} ({} recordings); seed {}.\n\n\
         {}\n![accuracy against latency](tradeoff.png)\n",
        experiment.name(),
        spec.feature_name(),
        spec.set.name(),
        study.pipeline.segmentation.name(),
        files(&study.train),
        train.len(),
        files(&study.test),
        test.len(),
        grid.seed,
        tradeoff.to_markdown()
    );
    let markdown_path = out.join("tradeoff.md");
    let json_path = out.join("tradeoff.json");
    std::fs::write(&markdown_path, &markdown).map_err(TactileError::writing(&markdown_path))?;
    std::fs::write(&json_path, serde_json::to_string_pretty(&tradeoff)?)
        .map_err(TactileError::writing(&json_path))?;
    Ok(TradeoffReport {
        tradeoff,
        markdown,
        markdown_path,
        json_path,
        png_path,
    })
}
