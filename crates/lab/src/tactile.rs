//! `crackbot tactile ...`: the tactile recordings, the authors' MAT-files and crackbot's CSV files.
//!
//! * `crackbot tactile convert INPUT... --out DIR|FILE` — converts recordings between `.mat` and `.csv`
//!   (`.csv` → `.csv` normalises the file). Inputs are files or folders (every `.mat`/`.csv` directly inside).
//! * `crackbot tactile eval --train PATH... --test PATH...` — trains on some recordings and tests on others:
//!   window-level and slide-level accuracy, precision, recall, confusion matrix, and for crack widths the
//!   regression error in mm.
//! * `crackbot tactile paper DATA...` — the paper's intersession grid: Markdown and JSON tables, confusion-matrix
//!   heat maps and accuracy box plots (PNG).
//! * `crackbot tactile tradeoff --train PATH... --test PATH... --out DIR` — the random forest's accuracy against
//!   its training time, size and single-window latency, over tree counts × depth limits (table and plot).

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use crackbot_recording::{collect_recordings, conversion_targets, write_recording, Recording};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{ExperimentArg, FormatArg};

/// Subcommands of `crackbot tactile`.
#[derive(Debug, Subcommand)]
pub enum TactileCommand {
    /// Convert recordings between the authors' .mat files and .csv (.csv → .csv normalises).
    ///
    /// With one input recording and `--out` ending in .csv or .mat, writes that file; otherwise `--out` is a
    /// folder (created if needed) and each input becomes `<stem>.<format>` there.
    Convert(ConvertArgs),
    /// Train on some recordings, test on others: window- and slide-level metrics (and width MAE).
    ///
    /// The experiment (surface recognition or crack width) is recognised from the labels.
    Eval(EvalArgs),
    /// Reproduce the paper's tables with its intersession protocol: every feature × channel set ×
    /// classifier, trained on one repetition and tested on each other one. Writes Markdown and JSON.
    Paper(PaperArgs),
    /// Random forest: accuracy against size, training time and single-window latency, for tree
    /// counts × depth limits. Writes tradeoff.md, tradeoff.json and tradeoff.png.
    Tradeoff(TradeoffArgs),
    /// Train the deployed models (recognition and/or width) on every recording given and write
    /// them (`recognition.ctm`, `width.ctm`) with a JSON summary each.
    Train(TrainArgs),
}

/// Arguments of `crackbot tactile train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Recordings of the surface-type experiment (files or folders).
    #[arg(long, num_args = 1..)]
    recognition: Vec<PathBuf>,
    /// Recordings of the crack-width experiment (files or folders).
    #[arg(long, num_args = 1..)]
    width: Vec<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "models/tactile")]
    out: PathBuf,
    /// Trees of each forest.
    #[arg(long, default_value_t = 100)]
    trees: usize,
    /// Depth limit of every tree (default: fully grown).
    #[arg(long)]
    max_depth: Option<usize>,
    /// Seed of the forests.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Train the recognition model on the surface-type recordings only. By default it also
    /// learns from the `--width` recordings (0 mm as "no crack", every other width as "crack"):
    /// the surface-type experiment has a single crack plate, and a model that never felt the
    /// others calls the authors' 1, 8 and 10 mm cracks "bump".
    #[arg(long)]
    recognition_type_only: bool,
    /// Who decides the recognition model's slide verdicts: `both` (the context forest's slide
    /// mean summed with that of the forest on the paper's absolute window features) or
    /// `context` (the context forest alone, whose features are relative to each slide's
    /// baseline). `both` by default: alone, the context forest reads every simulated crack as
    /// a wavy surface (models/tactile/MODEL_CARD.md, "Who votes").
    #[arg(long, value_enum, default_value_t = SlideVoteArg::Both)]
    recognition_vote: SlideVoteArg,
    /// Who decides the width model's slide verdicts. `context` by default: the window forest
    /// learns each width plate's fibre offsets, and a finger mounted with other offsets gets
    /// one width for every crack (models/tactile/MODEL_CARD.md, "Who votes").
    #[arg(long, value_enum, default_value_t = SlideVoteArg::Context)]
    width_vote: SlideVoteArg,
    /// Also train the width model on the simulator's width plates: the recordings of `crackbot
    /// sim dataset --experiment width --seed S`, simulated in memory, for each seed given (the
    /// recognition model is not given them). The simulated finger's proximity channel still
    /// differs from the real one on the narrow slots, and a model trained on the real finger
    /// alone reads about 60 % of simulated width slides right; with these it reads both
    /// (models/tactile/MODEL_CARD.md, "Real and simulated fingers").
    #[arg(long, num_args = 1.., value_name = "SEED")]
    width_sim_seeds: Vec<u64>,
    /// Also train the recognition model on the simulator's surface-type plates: the recordings
    /// of `crackbot sim dataset --experiment recognition --seed S`, simulated in memory, for
    /// each seed given. The authors' slides over the wavy plate all begin at one place against
    /// its waves, and a model trained on them alone misreads simulated wavy slides that begin
    /// elsewhere (`crates/sim/docs/calibration.md`, "It is where the stroke starts").
    #[arg(long, num_args = 1.., value_name = "SEED")]
    recognition_sim_seeds: Vec<u64>,
}

/// Arguments of `crackbot tactile tradeoff`.
#[derive(Debug, Args)]
pub struct TradeoffArgs {
    /// Training recordings (.mat or .csv files, or folders of them).
    #[arg(long, required = true, num_args = 1..)]
    train: Vec<PathBuf>,
    /// Test recordings (.mat or .csv files, or folders of them).
    #[arg(long, required = true, num_args = 1..)]
    test: Vec<PathBuf>,
    /// Output folder for tradeoff.md, tradeoff.json and tradeoff.png.
    #[arg(long, default_value = "out/tactile-tradeoff")]
    out: PathBuf,
    /// Tree counts to try.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2, 5, 10, 20, 50, 100, 200])]
    trees: Vec<usize>,
    /// Depth limits to try (`none`: fully grown).
    #[arg(long, value_delimiter = ',', default_values_t = ["none".to_string(), "20".to_string(), "12".to_string(), "8".to_string()])]
    depths: Vec<String>,
    /// Windows per timed batch of the latency measurement.
    #[arg(long, default_value_t = 1000)]
    batch: usize,
    #[command(flatten)]
    pipeline: PipelineArgs,
}

/// The window pipeline and forest seed shared by `eval` and `tradeoff`.
#[derive(Debug, Args)]
pub struct PipelineArgs {
    /// Windowed feature.
    #[arg(long, value_enum, default_value_t = FeatureArg::Mav)]
    feature: FeatureArg,
    /// Channel set.
    #[arg(long, value_enum, default_value_t = SetArg::D1d2p)]
    set: SetArg,
    /// Slide segmentation before windowing.
    #[arg(long, value_enum, default_value_t = SegmentationArg::Paper)]
    segmentation: SegmentationArg,
    /// Per-recording offset correction.
    #[arg(long, value_enum, default_value_t = NormaliseArg::None)]
    normalise: NormaliseArg,
    /// Experiment, when the labels fit both (only 0, 1, 2).
    #[arg(long, value_enum)]
    experiment: Option<ExperimentArg>,
    /// Seed of the forests.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

impl PipelineArgs {
    /// The paper's pipeline with these choices, windows `window`, no context.
    fn config(
        &self,
        window: crackbot_dsp::WindowConfig,
    ) -> crackbot_tactile::dataset::PipelineConfig {
        use crackbot_tactile::dataset::{Normalisation, PipelineConfig};
        PipelineConfig {
            segmentation: segmentation_of(self.segmentation),
            window,
            spec: crackbot_dsp::FeatureSpec::new(feature_of(self.feature), set_of(self.set)),
            normalisation: match self.normalise {
                NormaliseArg::None => Normalisation::None,
                NormaliseArg::Median => Normalisation::RecordingMedian,
            },
            min_slide_len: 100,
            context: None,
        }
    }
}

/// Arguments of `crackbot tactile paper`.
#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Folders (or files) of recordings, one experiment per folder, e.g. ../shared/data/tactile/type.
    #[arg(required = true)]
    data: Vec<PathBuf>,
    /// Output folder for paper-tables.md and paper-tables.json.
    #[arg(long, default_value = "out/tactile-paper")]
    out: PathBuf,
    /// Classifiers to run.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [ClassifierArg::Rf, ClassifierArg::Knn, ClassifierArg::Qda])]
    classifiers: Vec<ClassifierArg>,
    /// Trees of the random forest.
    #[arg(long, default_value_t = 100)]
    trees: usize,
    /// Slide segmentation before windowing.
    #[arg(long, value_enum, default_value_t = SegmentationArg::Paper)]
    segmentation: SegmentationArg,
    /// Seed of the forests.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Arguments of `crackbot tactile eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Training recordings (.mat or .csv files, or folders of them).
    #[arg(long, required_unless_present = "model", conflicts_with = "model", num_args = 1..)]
    train: Vec<PathBuf>,
    /// Evaluate a deployed model file (`crackbot tactile train`) instead of training one; its own
    /// pipeline is used and the pipeline options are ignored.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Test recordings (.mat or .csv files, or folders of them).
    #[arg(long, required = true, num_args = 1..)]
    test: Vec<PathBuf>,
    #[command(flatten)]
    pipeline: PipelineArgs,
    /// Classifier.
    #[arg(long, value_enum, default_value_t = ClassifierArg::Rf)]
    classifier: ClassifierArg,
    /// Trees of the random forests (classifier and width regressor).
    #[arg(long, default_value_t = 100)]
    trees: usize,
    /// Print one JSON object (window_accuracy, slide_accuracy, width_mae_mm, …).
    #[arg(long)]
    json: bool,
    /// Window length in samples (10 = 25 ms in the paper).
    #[arg(long, default_value_t = 10)]
    window_len: usize,
    /// Step between windows in samples (2 in the paper).
    #[arg(long, default_value_t = 2)]
    window_step: usize,
    /// Add causal context features to each window: levels relative to the slide's own baseline,
    /// multi-scale spans (--context-scales), the slide so far and the direction (see
    /// crackbot_tactile::context). Never the x position. The slide verdicts then also take the
    /// vote of a forest on the paper's window features (see --slide-vote).
    #[arg(long)]
    context: bool,
    /// Context span lengths in samples (with --context).
    #[arg(long, value_delimiter = ',', default_values_t = [200, 1200, 2000])]
    context_scales: Vec<usize>,
    /// Samples at each slide's start whose median is its baseline (with --context).
    #[arg(long, default_value_t = 40)]
    context_baseline: usize,
    /// Leave out the slide-so-far minimum/maximum/range (with --context).
    #[arg(long)]
    no_prefix: bool,
    /// Leave out the sliding direction (with --context).
    #[arg(long)]
    no_direction: bool,
    /// Keep the window's own absolute features beside the context features (with --context).
    #[arg(long)]
    keep_window: bool,
    /// Stop the context spans at each slide's first sample (with --context); by default they
    /// reach back into the previous slides of the same recording, the finger's memory of a
    /// continuous exploration.
    #[arg(long)]
    within_slides: bool,
    /// Who decides a slide's verdict (with --context): `both` sums the slide means of the context
    /// forest and of a forest on the paper's window features; `context` uses the context forest
    /// alone.
    #[arg(long, value_enum, default_value_t = SlideVoteArg::Both)]
    slide_vote: SlideVoteArg,
    /// Add shape values per span (with --context): longest run below / above half the span's
    /// departure from the baseline, and the span's absolute minimum and maximum.
    #[arg(long)]
    context_shape: bool,
    /// Random forests: candidate features per split as a fraction of all (default: sqrt for the
    /// classifier, all for the width regressor).
    #[arg(long)]
    max_features: Option<f64>,
    /// Random forests: maximum depth (default unlimited).
    #[arg(long)]
    max_depth: Option<usize>,
    /// Random forests: minimum samples per leaf (default 1).
    #[arg(long)]
    min_samples_leaf: Option<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SlideVoteArg {
    /// Context forest + paper-feature forest.
    Both,
    /// Context forest alone.
    Context,
}

impl From<SlideVoteArg> for crackbot_tactile::evaluation::SlideVote {
    fn from(v: SlideVoteArg) -> Self {
        match v {
            SlideVoteArg::Both => Self::Both,
            SlideVoteArg::Context => Self::Context,
        }
    }
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum FeatureArg {
    Raw,
    Mav,
    Rms,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SetArg {
    /// Proximity only.
    P,
    /// D1, D2, D3.
    D1d2d3,
    /// D1, D2, D3 and P.
    D1d2d3p,
    /// D1, D2 and P.
    D1d2p,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
enum ClassifierArg {
    Rf,
    Knn,
    Qda,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum SegmentationArg {
    /// Whole slides.
    None,
    /// The paper's eq. 2 (faithful reading).
    Paper,
    /// crackbot's robust segmentation.
    Robust,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum NormaliseArg {
    /// Raw ADC counts.
    None,
    /// Subtract each channel's median over the recording.
    Median,
}

/// Arguments of `crackbot tactile convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Recordings (.mat or .csv), or folders holding them (not searched recursively).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Output file (.csv or .mat; one input recording only) or folder.
    #[arg(long, short)]
    out: PathBuf,
    /// Form of the files written into an output folder.
    #[arg(long, value_enum, default_value_t = FormatArg::Csv)]
    format: FormatArg,
    /// The inputs are width-experiment recordings: write them relabelled for the surface-type
    /// experiment (0 mm as "no crack", every other width as "crack"), e.g. to test a recognition
    /// model on every crack width with `tactile eval --model`.
    #[arg(long)]
    width_as_recognition: bool,
}

/// Runs a `crackbot tactile` subcommand.
pub fn run(cmd: TactileCommand) -> Result<()> {
    match cmd {
        TactileCommand::Convert(args) => convert(args),
        TactileCommand::Eval(args) => eval(args),
        TactileCommand::Paper(args) => paper(args),
        TactileCommand::Tradeoff(args) => tradeoff(args),
        TactileCommand::Train(args) => train(args),
    }
}

fn convert(args: ConvertArgs) -> Result<()> {
    // Everything is read (and checked) before anything is written.
    let mut recordings = collect_recordings(&args.inputs)?;
    if args.width_as_recognition {
        recordings = widths_as_recognition(&recordings)?;
    }
    let inputs: Vec<PathBuf> = recordings.iter().map(|(p, _)| p.clone()).collect();
    let targets = conversion_targets(&inputs, &args.out, args.format.into())?;
    let mut stdout = std::io::stdout().lock();
    for ((input, rec), target) in recordings.iter().zip(&targets) {
        write_recording(target, rec)?;
        // A closed stdout (e.g. piped into `head`) must not stop the conversion.
        let _ = writeln!(
            stdout,
            "{} → {}: {}",
            input.display(),
            target.display(),
            describe(rec)
        );
    }
    Ok(())
}

/// Width-experiment recordings relabelled for the surface-type experiment
/// ([`Recording::width_as_recognition`]); a label that is no width names its file.
fn widths_as_recognition(recordings: &[(PathBuf, Recording)]) -> Result<Vec<(PathBuf, Recording)>> {
    recordings
        .iter()
        .map(|(path, rec)| {
            let relabelled = rec
                .width_as_recognition()
                .with_context(|| format!("{} (read as a width recording)", path.display()))?;
            Ok((path.clone(), relabelled))
        })
        .collect()
}

/// One line about a recording: rows, slides, label and repetition.
fn describe(rec: &Recording) -> String {
    let label = rec
        .label()
        .map_or_else(|| "mixed".to_string(), |l| l.to_string());
    let repetition = rec
        .repetition()
        .map_or_else(|| "mixed".to_string(), |r| r.to_string());
    format!(
        "{} rows, {} slides, label {label}, repetition {repetition}",
        rec.len(),
        rec.slides().len()
    )
}

/// A progress bar on stderr for one forest after another, when stderr is a terminal and `show`:
/// `tree(done, total)` after each finished tree of a forest of `total` (reports come one at a time,
/// `done` = 1..=total). The library reports, this draws.
fn tree_bars(show: bool) -> impl FnMut(usize, usize) + Send {
    let show = show && std::io::stderr().is_terminal();
    let mut bar: Option<ProgressBar> = None;
    move |done, total| {
        if !show {
            return;
        }
        let b = bar.get_or_insert_with(|| {
            let b = ProgressBar::new(total as u64);
            if let Ok(style) = ProgressStyle::with_template(
                "training {bar:40} {pos}/{len} trees [{elapsed_precise}, eta {eta}]",
            ) {
                b.set_style(style);
            }
            b
        });
        b.set_position(done as u64);
        if done >= total {
            b.finish_and_clear();
            bar = None;
        }
    }
}

fn eval(args: EvalArgs) -> Result<()> {
    use crackbot_dsp::WindowConfig;
    use crackbot_tactile::context::ContextConfig;
    use crackbot_tactile::dataset::PipelineConfig;
    use crackbot_tactile::eval::ForestTuning;
    use crackbot_tactile::evaluation::{evaluate, EvalConfig};

    let config = EvalConfig {
        experiment: args.pipeline.experiment.map(Into::into),
        pipeline: PipelineConfig {
            context: args.context.then(|| ContextConfig {
                scales: args.context_scales.clone(),
                baseline_len: args.context_baseline,
                prefix: !args.no_prefix,
                direction: !args.no_direction,
                keep_window: args.keep_window,
                across_slides: !args.within_slides,
                shape: args.context_shape,
            }),
            ..args.pipeline.config(WindowConfig {
                len: args.window_len,
                step: args.window_step,
            })
        },
        classifier: classifier_of(args.classifier, args.trees),
        n_trees: args.trees,
        tuning: ForestTuning {
            max_features_fraction: args.max_features,
            max_depth: args.max_depth,
            min_samples_leaf: args.min_samples_leaf,
        },
        seed: args.pipeline.seed,
        slide_vote: args.slide_vote.into(),
    };
    let report = match &args.model {
        Some(path) => {
            let model = crackbot_tactile::model::TactileModel::load(path)?;
            crackbot_tactile::evaluation::evaluate_model(&model, &args.test)?
        }
        None => {
            let mut tree = tree_bars(!args.json);
            evaluate(&config, &args.train, &args.test, |_, done, total| {
                tree(done, total);
            })?
        }
    };
    if args.json {
        // Through a `Value`: its maps sort their keys, at every level, as this output always has.
        println!("{}", serde_json::to_value(&report)?);
        return Ok(());
    }
    println!(
        "{} experiment, {} on {} {}, segmentation {}: trained on {} windows of {} recordings in {:.2} s, tested on {} windows / {} slides of {} recordings",
        report.experiment,
        report.classifier,
        report.feature,
        report.set,
        report.segmentation,
        report.train_windows,
        report.train_recordings,
        report.train_seconds,
        report.test_windows,
        report.test_slides,
        report.test_recordings
    );
    for (title, accuracy, precision, recall, rows) in [
        (
            "windows",
            report.window_accuracy,
            report.window_precision,
            report.window_recall,
            &report.window_confusion,
        ),
        (
            "slides",
            report.slide_accuracy,
            report.slide_precision,
            report.slide_recall,
            &report.slide_confusion,
        ),
    ] {
        println!(
            "\n{title}: accuracy {:.2}%, weighted precision {:.2}%, weighted recall {:.2}%",
            100.0 * accuracy,
            100.0 * precision,
            100.0 * recall
        );
        print_confusion(&report.classes, rows);
    }
    if let Some(mae) = report.slide_width_reported_mae_mm {
        println!("\nreported width (the slide verdict's class): MAE {mae:.2} mm per slide");
    }
    if let (Some(window_mae), Some(slide_mae)) = (report.width_mae_mm, report.slide_width_mae_mm) {
        println!(
            "\nwidth regression ({} trees): MAE {:.2} mm per window, {:.2} mm per slide",
            args.trees, window_mae, slide_mae
        );
    }
    Ok(())
}

fn print_confusion(names: &[String], rows: &[Vec<u64>]) {
    const CORNER: &str = "true \\ predicted";
    let label = names
        .iter()
        .map(String::len)
        .max()
        .unwrap_or(0)
        .max(CORNER.len());
    let cell = names.iter().map(String::len).max().unwrap_or(0).max(7);
    print!("  {CORNER:>label$} |");
    for n in names {
        print!(" {n:>cell$}");
    }
    println!();
    for (name, row) in names.iter().zip(rows) {
        print!("  {name:>label$} |");
        for v in row {
            print!(" {v:>cell$}");
        }
        println!();
    }
}

fn segmentation_of(arg: SegmentationArg) -> crackbot_tactile::dataset::Segmentation {
    use crackbot_dsp::{PaperSegmentation, RobustSegmentation, SegmentationMethod};
    use crackbot_tactile::dataset::Segmentation;
    match arg {
        SegmentationArg::None => Segmentation::None,
        SegmentationArg::Paper => {
            Segmentation::Method(SegmentationMethod::Paper(PaperSegmentation::default()))
        }
        SegmentationArg::Robust => {
            Segmentation::Method(SegmentationMethod::Robust(RobustSegmentation::default()))
        }
    }
}

fn classifier_of(arg: ClassifierArg, trees: usize) -> crackbot_tactile::eval::ClassifierKind {
    use crackbot_tactile::eval::ClassifierKind;
    match arg {
        ClassifierArg::Rf => ClassifierKind::Forest { n_trees: trees },
        ClassifierArg::Knn => ClassifierKind::Knn,
        ClassifierArg::Qda => ClassifierKind::Qda,
    }
}

fn paper(args: PaperArgs) -> Result<()> {
    use crackbot_plots::tactile::{paper_plots, plots_markdown};
    use crackbot_tactile::dataset::PipelineConfig;
    use crackbot_tactile::paper::{paper_study, PaperConfig, PaperEvent};
    use crackbot_tactile::TactileError;

    let config = PaperConfig {
        classifiers: args
            .classifiers
            .iter()
            .map(|&c| classifier_of(c, args.trees))
            .collect(),
        n_trees: args.trees,
        base: PipelineConfig {
            segmentation: segmentation_of(args.segmentation),
            ..PipelineConfig::default()
        },
        seed: args.seed,
    };
    config.validate()?;
    // Fail before the long grid, not after it, when the plots cannot draw text.
    crackbot_plots::load_font()?;
    let mut bar: Option<ProgressBar> = None;
    let report = paper_study(
        &config,
        &args.data,
        &args.out,
        |event| match event {
            PaperEvent::Folder {
                experiment, cells, ..
            } => {
                let b = ProgressBar::new(cells as u64);
                b.set_style(
                    ProgressStyle::with_template(
                        "{msg} [{elapsed_precise}] {bar:30} {pos}/{len} cells",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
                );
                b.set_message(experiment.name());
                bar = Some(b);
            }
            PaperEvent::Cell { experiment, cell } => {
                let line = format!(
                    "{} {:<4} {} {:<9} accuracy {:6.2}% ± {:5.2}  slides {:6.2}%",
                    experiment.name(),
                    cell.classifier,
                    cell.feature,
                    cell.set,
                    100.0 * cell.accuracy_mean,
                    100.0 * cell.accuracy_std,
                    100.0 * cell.slide_accuracy_mean
                );
                match &bar {
                    Some(b) if !b.is_hidden() => {
                        b.inc(1);
                        b.println(line);
                    }
                    _ => eprintln!("{line}"),
                }
            }
            PaperEvent::FolderDone { .. } => {
                if let Some(b) = bar.take() {
                    b.finish_and_clear();
                }
            }
            _ => {}
        },
        |out, tables| {
            let plots = paper_plots(out, tables).map_err(TactileError::figure)?;
            Ok(plots_markdown(&plots, out))
        },
    )?;
    println!("{}", report.markdown);
    println!(
        "wrote {} and {}",
        report.markdown_path.display(),
        report.json_path.display()
    );
    Ok(())
}

fn feature_of(arg: FeatureArg) -> crackbot_dsp::Feature {
    use crackbot_dsp::Feature;
    match arg {
        FeatureArg::Raw => Feature::Raw,
        FeatureArg::Mav => Feature::Mav,
        FeatureArg::Rms => Feature::Rms,
    }
}

fn set_of(arg: SetArg) -> crackbot_dsp::FeatureSet {
    use crackbot_dsp::FeatureSet;
    match arg {
        SetArg::P => FeatureSet::P,
        SetArg::D1d2d3 => FeatureSet::D1D2D3,
        SetArg::D1d2d3p => FeatureSet::D1D2D3P,
        SetArg::D1d2p => FeatureSet::D1D2P,
    }
}

fn parse_depth(s: &str) -> Result<Option<usize>> {
    let s = s.trim();
    if s.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    match s.parse::<usize>() {
        Ok(d) if d >= 1 => Ok(Some(d)),
        _ => bail!("--depths: {s:?} is neither `none` nor a depth of at least 1"),
    }
}

fn tradeoff(args: TradeoffArgs) -> Result<()> {
    use crackbot_dsp::WindowConfig;
    use crackbot_tactile::tradeoff::{depth_name, tradeoff_study, TradeoffConfig, TradeoffStudy};

    // Errors in this order: trees and batch (checked beside the default depths), the depths, the font.
    let mut grid = TradeoffConfig {
        n_trees: args.trees.clone(),
        seed: args.pipeline.seed,
        latency_batch: args.batch,
        ..TradeoffConfig::default()
    };
    grid.validate()?;
    grid.max_depths = args
        .depths
        .iter()
        .map(|d| parse_depth(d))
        .collect::<Result<_>>()?;
    crackbot_plots::load_font()?;
    let study = TradeoffStudy {
        train: args.train.clone(),
        test: args.test.clone(),
        experiment: args.pipeline.experiment.map(Into::into),
        pipeline: args.pipeline.config(WindowConfig::default()),
        grid,
    };
    let report = tradeoff_study(
        &study,
        &args.out,
        |r| {
            eprintln!(
                "max depth {:>4}, {:>3} trees: {:>8} nodes, trained in {:7.3} s, {:8.2} µs/window, window accuracy {:6.2}%, slides {:6.2}%",
                depth_name(r.max_depth),
                r.n_trees,
                r.n_nodes,
                r.train_seconds,
                1e6 * r.latency_seconds,
                100.0 * r.window_accuracy,
                100.0 * r.slide_accuracy
            );
        },
        |png, result| {
            crackbot_plots::tactile::tradeoff_png(png, result)
                .map_err(crackbot_tactile::TactileError::figure)
        },
    )?;
    println!("{}", report.markdown);
    println!(
        "wrote {}, {} and {}",
        report.markdown_path.display(),
        report.json_path.display(),
        report.png_path.display()
    );
    Ok(())
}

/// The simulator's plates of `experiment` for each of `seeds`, in memory, named
/// `sim-seed<S>-<stem>` (the names the model's training facts list).
fn simulated_plates(
    experiment: crackbot_sim::experiment::Experiment,
    seeds: &[u64],
) -> Result<Vec<(PathBuf, Recording)>> {
    use crackbot_sim::experiment::{simulate_named, ExperimentConfig};
    let mut out = Vec::new();
    for &seed in seeds {
        let config = ExperimentConfig::paper(experiment, seed);
        let total = config.surfaces().len() * config.recordings as usize;
        let what = format!("the {} experiment, seed {seed}", experiment.name());
        let pb = crate::sim::bar(total, &format!("simulating {what}"));
        out.extend(
            simulate_named(&config, |done, _| pb.set_position(done as u64))
                .with_context(|| format!("simulating {what}"))?,
        );
        pb.finish_and_clear();
    }
    Ok(out)
}

fn train(args: TrainArgs) -> Result<()> {
    use crackbot_tactile::dataset::Experiment;
    use crackbot_tactile::model::{TactileModel, TrainConfig};
    if args.recognition.is_empty() && args.width.is_empty() {
        bail!("nothing to train: give --recognition and/or --width recordings");
    }
    if !args.width_sim_seeds.is_empty() && args.width.is_empty() {
        bail!("--width-sim-seeds adds simulated plates to the width model: give --width recordings too");
    }
    if !args.recognition_sim_seeds.is_empty() && args.recognition.is_empty() {
        bail!(
            "--recognition-sim-seeds adds simulated plates to the recognition model: give \
             --recognition recordings too"
        );
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| anyhow::anyhow!("creating {}: {e}", args.out.display()))?;
    let config = |vote: SlideVoteArg| TrainConfig {
        n_trees: args.trees,
        max_depth: args.max_depth,
        seed: args.seed,
        slide_vote: vote.into(),
    };
    // Each set is read once: the width recordings serve both models (recognition first, then
    // the width model takes them).
    let mut widths = collect_recordings(&args.width)?;
    for (experiment, paths) in [
        (Experiment::Recognition, &args.recognition),
        (Experiment::Width, &args.width),
    ] {
        if paths.is_empty() {
            continue;
        }
        let (recordings, pooled) = match experiment {
            Experiment::Recognition => {
                let mut recordings = collect_recordings(paths)?;
                recordings.extend(simulated_plates(experiment, &args.recognition_sim_seeds)?);
                let pooled = if args.recognition_type_only {
                    Vec::new()
                } else {
                    widths_as_recognition(&widths)?
                };
                let n = pooled.len();
                recordings.extend(pooled);
                (recordings, n)
            }
            Experiment::Width => {
                let mut recordings = std::mem::take(&mut widths);
                recordings.extend(simulated_plates(experiment, &args.width_sim_seeds)?);
                (recordings, 0)
            }
        };
        let of_them = if pooled > 0 {
            format!(
                " ({pooled} of them width plates read as no crack / crack; \
                 --recognition-type-only leaves them out)"
            )
        } else {
            String::new()
        };
        eprintln!(
            "{}: {} recordings{of_them}, training the context forest, the window forest{} ({} trees each)",
            experiment.name(),
            recordings.len(),
            if experiment == Experiment::Width {
                " and the width regressor"
            } else {
                ""
            },
            args.trees
        );
        let mut bar = tree_bars(true);
        let vote = match experiment {
            Experiment::Recognition => args.recognition_vote,
            Experiment::Width => args.width_vote,
        };
        let model = TactileModel::train(
            &recordings,
            Some(experiment),
            &config(vote),
            &mut |_, done, total| bar(done, total),
        )?;
        let path = args.out.join(format!("{}.ctm", experiment.name()));
        model.save(&path)?;
        let summary = args.out.join(format!("{}.json", experiment.name()));
        let bytes = std::fs::read(&path)?;
        let json = serde_json::json!({
            "file": path.file_name().map(|f| f.to_string_lossy().to_string()),
            "bytes": bytes.len(),
            "format_version": crackbot_tactile::model::FORMAT_VERSION,
            "experiment": experiment.name(),
            "classes": model.header.classes,
            "training": model.header.training,
            "pipeline": model.header.pipeline,
            "slide_vote": model.header.slide_vote,
            "context_forest_nodes": model.context_forest.n_nodes(),
            "window_forest_nodes": model.window_forest.n_nodes(),
            "width_regressor_nodes": model.width.as_ref().map(crackbot_forest::RandomForestRegressor::n_nodes),
        });
        std::fs::write(&summary, serde_json::to_string_pretty(&json)? + "\n")?;
        println!(
            "wrote {} ({} bytes, {} windows of {} slides, {:.1} s) and {}",
            path.display(),
            bytes.len(),
            model.header.training.windows,
            model.header.training.slides,
            model.header.training.seconds,
            summary.display()
        );
    }
    Ok(())
}
