//! `crackbot-lab mission trials|exploration`: the visual-tactile paper's online experiments in
//! simulation, each a series of whole missions (`crackbot_research`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use crackbot_mission::inspect::InspectConfig;
use crackbot_research::{
    detection_trials, exploration_markdown, exploration_times, ExperimentConfig,
};
use crackbot_sim::Scene;

/// The experiments.
#[derive(Debug, Subcommand)]
pub enum MissionCommand {
    /// Correct detections over trials on random scenes, vision only vs vision + tactile.
    Trials(TrialsArgs),
    /// Exploration time of a 200 × 100 mm plate, tactile only (per γ) vs vision + tactile.
    Exploration(ExplorationArgs),
}

/// Shared flags.
#[derive(Debug, Args)]
pub struct Common {
    /// Folder for the tables and every mission's folder.
    #[arg(long, default_value = "out/experiments")]
    out: PathBuf,
    /// Simulation speed-up.
    #[arg(long, default_value_t = 8.0)]
    speedup: f64,
    /// Give every crack the cross-section of the authors' printed plates (the profile the
    /// deployed tactile models were trained on) instead of the scene's own.
    #[arg(long)]
    printed_cracks: bool,
    /// Strokes across each candidate (forth and back count as two).
    #[arg(long, default_value_t = 1)]
    passes: u32,
    /// Slide speed, mm/s (default: 4.6, the speed of the authors' recordings).
    #[arg(long)]
    slide_speed: Option<f64>,
    /// Shortest stroke across a candidate, mm (default: 6; the paper's is 16).
    #[arg(long)]
    stroke_mm: Option<f64>,
    /// Sound surface wanted beyond a candidate's edge and the finger's reach on each side of its stroke,
    /// mm (default: 0.5).
    #[arg(long)]
    margin_mm: Option<f64>,
    /// How far beyond a candidate's edge the finger still feels it, mm: each stroke starts and
    /// ends this far plus the margin beyond the edge (default: the proximity fibre's reach,
    /// 2.4 mm; 4.4 keeps the whole tip on sound surface).
    #[arg(long)]
    reach_mm: Option<f64>,
    /// What the finger touches: every crack a detection holds (cracks) or every detection once
    /// across its main axis (detections).
    #[arg(long, default_value = "cracks", value_parser = ["cracks", "detections"])]
    candidates: String,
    /// Confirm a crack on the recognition model's vote alone, also where the proximity channel
    /// saw no dip (by default a crack must show one).
    #[arg(long)]
    confirm_without_dip: bool,
    /// Fused missions: height of the print check's raised pass over each candidate the finger
    /// confirmed, mm above the plate (a print's dip keeps its share of the signal there, a
    /// crack's does not); 0 turns the check off.
    #[arg(long, default_value_t = crackbot_mission::PRINT_CHECK_HEIGHT_MM)]
    print_check_mm: f64,
    /// Shallowest proximity dip a confirmed crack needs, counts (100 suits missions without the
    /// print check).
    #[arg(long, default_value_t = crackbot_mission::inspect::MIN_DIP_COUNTS)]
    min_dip_counts: f64,
    /// Fused missions with the print check: a pass the recognition model read as "no crack"
    /// while doubting it (a surface unlike training, or a weak vote) still stands for a crack
    /// when its proximity dip is at least this confident (0–1), and the print check decides;
    /// 0: the model's verdict always stands.
    #[arg(long, default_value_t = crackbot_mission::inspect::DOUBTED_DIP_CONFIDENCE)]
    doubted_dip_confidence: f64,
    /// Fused missions: report confirmed candidates whose detections continue each other
    /// across at most this gap (mm, within 40° of one direction) as one crack; 0 reports each.
    #[arg(long, default_value_t = crackbot_mission::inspect::PIECE_GAP_MM)]
    piece_gap_mm: f64,
    /// Fused missions: also report two confirmed candidates as one crack when the straight line
    /// between the points where their strokes met it runs along both and over the detector's
    /// crack map, off it for at most this much (mm); pieces joined by --piece-gap-mm must then
    /// also have that line on the map but for their gap plus this much. Negative: off.
    #[arg(long, default_value_t = crackbot_mission::inspect::PIECE_TRACE_GAP_MM, allow_negative_numbers = true)]
    piece_trace_gap_mm: f64,
    /// Deployed recognition model (default: models/tactile/recognition.ctm).
    #[arg(long)]
    recognition_model: Option<PathBuf>,
    /// Deployed width model (default: models/tactile/width.ctm).
    #[arg(long)]
    width_model: Option<PathBuf>,
    /// Fused missions: detections scoring below this are not touched (vision-only missions
    /// report from 0.3).
    #[arg(long, default_value_t = 0.3)]
    proposal_min_score: f32,
    /// ONNX crack detector (default: models/detector/crackseg-tiles/crack-detector-320.onnx), e.g. the
    /// 416-pixel export of the same weights.
    #[arg(long)]
    detector: Option<PathBuf>,
}

/// `mission trials`.
#[derive(Debug, Args)]
pub struct TrialsArgs {
    #[command(flatten)]
    common: Common,
    /// Number of trials (scenes).
    #[arg(long, default_value_t = 10)]
    trials: u64,
    /// Seed of the first scene.
    #[arg(long, default_value_t = 1000)]
    seed: u64,
    /// Trials run at once. Each is a simulated robot running in real time over the speed-up:
    /// give each a core and a half (on a 2-core machine, 1; two at once make each other's
    /// sensor stream look stalled).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=256))]
    jobs: u64,
}

/// `mission exploration`.
#[derive(Debug, Args)]
pub struct ExplorationArgs {
    #[command(flatten)]
    common: Common,
    /// Scene (default: the built-in default scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// γ values of the tactile-only scans.
    #[arg(long, value_delimiter = ',', default_value = "0.25,0.5,0.75")]
    gamma: Vec<f64>,
}

fn base(common: &Common) -> Result<ExperimentConfig> {
    std::fs::create_dir_all(&common.out)
        .with_context(|| format!("creating {}", common.out.display()))?;
    let mut template = InspectConfig::new(Scene::builtin_default(), &common.out);
    template.plan.planner.passes = common.passes;
    if !(0.0..=1.0).contains(&common.proposal_min_score) {
        anyhow::bail!(
            "--proposal-min-score must lie in [0, 1], got {}",
            common.proposal_min_score
        );
    }
    template.perceive.proposal_min_score = common.proposal_min_score;
    template.perceive.candidates = common.candidates.parse().map_err(anyhow::Error::msg)?;
    template.judge.require_dip = !common.confirm_without_dip;
    template.print_check.height_mm =
        crackbot_mission::print_check_height(common.print_check_mm).context("--print-check-mm")?;
    template.touch.min_dip_counts = common.min_dip_counts;
    template.judge.doubted_dip_confidence =
        crackbot_mission::inspect::doubted_dip_confidence(common.doubted_dip_confidence)
            .context("--doubted-dip-confidence")?;
    template.pieces.gap_mm = (common.piece_gap_mm != 0.0).then_some(common.piece_gap_mm);
    template.pieces.trace_gap_mm =
        (common.piece_trace_gap_mm >= 0.0).then_some(common.piece_trace_gap_mm);
    if let Some(p) = &common.recognition_model {
        template.touch.recognition_model = p.clone();
    }
    if let Some(p) = &common.width_model {
        template.touch.width_model = p.clone();
    }
    if common.detector.is_some() {
        template.perceive.detector_model = common.detector.clone();
    }
    if let Some(v) = common.stroke_mm {
        template.plan.planner.min_stroke_mm = v;
    }
    if let Some(v) = common.margin_mm {
        template.plan.planner.margin_mm = v;
        template.plan.planner.min_margin_mm = template.plan.planner.min_margin_mm.min(v);
    }
    if let Some(v) = common.reach_mm {
        template.plan.planner.reach_mm = v;
    }
    if let Some(v) = common.slide_speed {
        template.plan.planner.slide_speed_mm_s = v;
    }
    Ok(ExperimentConfig {
        out_dir: common.out.clone(),
        speedup: common.speedup,
        template,
        printed_cracks: common.printed_cracks,
        jobs: 1,
    })
}

/// Runs an experiment and writes its Markdown and JSON tables.
pub fn run(cmd: MissionCommand) -> Result<()> {
    match cmd {
        MissionCommand::Trials(a) => {
            let b = ExperimentConfig {
                jobs: a.jobs as usize,
                ..base(&a.common)?
            };
            let report = detection_trials(&b, a.seed, a.trials, |seed, t| {
                eprintln!(
                    "trial {seed}: vision {:.0} %, vision + tactile {:.0} %",
                    100.0 * t.vision.correct_fraction(),
                    100.0 * t.fused.correct_fraction()
                );
            })?;
            let md = report.markdown();
            std::fs::write(a.common.out.join("trials.md"), &md)?;
            std::fs::write(
                a.common.out.join("trials.json"),
                serde_json::to_string_pretty(&report)?,
            )?;
            println!("{md}");
        }
        MissionCommand::Exploration(a) => {
            let b = base(&a.common)?;
            let mut scene = Scene::load_or_default(a.scene.as_deref())?;
            if a.common.printed_cracks {
                scene = crackbot_research::as_printed(&scene);
            }
            let rows = exploration_times(&b, &scene, &a.gamma, |r| {
                eprintln!("{:?} γ {:?}: {:.1} s", r.mode, r.gamma, r.exploration_s);
            })?;
            let md = exploration_markdown(&rows);
            std::fs::write(a.common.out.join("exploration.md"), &md)?;
            std::fs::write(
                a.common.out.join("exploration.json"),
                serde_json::to_string_pretty(&rows)?,
            )?;
            println!("{md}");
        }
    }
    Ok(())
}
