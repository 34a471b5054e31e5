//! `crackbot-lab eval-detector` and `crackbot-lab detector-tradeoff`: the detector's COCO
//! metrics and its accuracy against run time. The work is `crackbot-vision`'s, the figure
//! `crackbot-plots`'; this module parses, draws progress bars and prints.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use crackbot_vision::benchmark::{map_params, Benchmark, EvalReport};
use crackbot_vision::coco::{save_results, CocoMetrics};
use crackbot_vision::model::{build_detector, trained_models, DetectorChoice, DetectorKind};
use crackbot_vision::preprocess::PostprocessParams;
use crackbot_vision::tradeoff::{self, TradeoffConfig};
use crackbot_vision::Detector;
use indicatif::{ProgressBar, ProgressStyle};

/// Detector choice (the same flags as `crackbot detect`).
#[derive(Debug, Args)]
pub struct DetectorArgs {
    /// Detector: `onnx` (the trained model, ONNX Runtime) or `classical` (the edge-based
    /// baseline, no model).
    #[arg(
        long,
        default_value = "onnx",
        value_parser = PossibleValuesParser::new(DetectorKind::ALL.map(DetectorKind::name))
            .try_map(|s| s.parse::<DetectorKind>())
    )]
    detector: DetectorKind,
    /// ONNX model (default: models/detector/crackseg-tiles/crack-detector-320.onnx of this repository).
    #[arg(long)]
    model: Option<PathBuf>,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = 1)]
    threads: usize,
}

impl DetectorArgs {
    /// The detector these flags name, built with `params` (errors name the model file).
    fn build(&self, params: PostprocessParams) -> Result<Box<dyn Detector>> {
        let choice = DetectorChoice {
            kind: self.detector,
            model: self.model.clone(),
            threads: self.threads,
        };
        Ok(build_detector(&choice, params)?)
    }
}

/// Arguments of `crackbot eval-detector`.
#[derive(Debug, Args)]
pub struct EvalDetectorArgs {
    /// COCO ground truth (images, annotations, categories).
    #[arg(long)]
    coco: PathBuf,
    /// Folder the COCO `file_name`s are relative to (default: the COCO file's folder).
    #[arg(long)]
    images: Option<PathBuf>,
    #[command(flatten)]
    detector: DetectorArgs,
    /// Write the detections as a COCO results file.
    #[arg(long)]
    save_results: Option<PathBuf>,
    /// Print one JSON object (map, map50, ar100, …).
    #[arg(long)]
    json: bool,
}

/// A progress bar over the images of a benchmark (hidden when `quiet`).
fn image_bar(total: usize, detector: &str, quiet: bool) -> ProgressBar {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(total as u64).with_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} images, {eta} left")
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        )
    };
    bar.set_message(detector.to_string());
    bar
}

/// `crackbot eval-detector`.
pub fn eval_detector(args: EvalDetectorArgs) -> Result<()> {
    let bench = Benchmark::load(&args.coco, args.images.as_deref())?;
    let mut detector = args.detector.build(map_params())?;
    let bar = image_bar(bench.gt.images.len(), &detector.name(), args.json);
    let run = bench.run(detector.as_mut(), |p| bar.set_position(p.done as u64))?;
    bar.finish_and_clear();
    if let Some(path) = &args.save_results {
        save_results(path, &run.results)?;
    }
    let report = EvalReport::new(&bench, &run);
    if args.json {
        println!("{}", serde_json::to_value(&report)?);
        return Ok(());
    }
    println!(
        "{} on {} ({} images, {} boxes): {} detections, median {:.1} ms per image",
        report.detector,
        report.coco,
        report.images,
        report.ground_truth_boxes,
        report.detections,
        report.ms_per_image
    );
    for (name, v) in CocoMetrics::NAMES.iter().zip(report.metrics.stats()) {
        println!("  {name:<10} {v:.4}");
    }
    for p in &report.pixel {
        println!(
            "  pixels, tolerance {} px ({} masks): ODS F1 {:.3} (P {:.3}, R {:.3} at {:.2}), OIS F1 {:.3}, at 0.5: F1 {:.3}",
            p.tolerance_px,
            p.images,
            p.ods.f1,
            p.ods.precision,
            p.ods.recall,
            p.ods.threshold,
            p.ois_f1,
            p.at_half.f1
        );
    }
    if let Some(c) = &report.cracks {
        println!(
            "  cracks of the masks: {}/{} found ({:.1}%: the map ≥ {} within {} px of more than half the centre line; {} specks under {} px left out)",
            c.found,
            c.cracks,
            100.0 * c.recall,
            crackbot_vision::crack_recall::MAP_THRESHOLD,
            crackbot_vision::crack_recall::TOLERANCE_PX,
            c.specks,
            crackbot_vision::crack_recall::MIN_LINE_PX
        );
    }
    if let Some(s) = &report.scene {
        println!(
            "  rendered scenes: {}/{} cracks found ({:.1}%; {} by IoU ≥ 0.5 alone), {}/{} decoys proposed, {} other detections",
            s.found,
            s.cracks,
            100.0 * s.recall,
            s.found_by_iou,
            s.decoys_proposed,
            s.decoys,
            s.other_detections
        );
        for b in &s.by_width {
            let hi = b.up_to_mm.map_or("∞".to_string(), |h| format!("{h}"));
            println!(
                "    width ({}, {hi}] mm: {}/{} found",
                b.above_mm, b.found, b.cracks
            );
        }
        if let Some(p) = &s.pieces {
            println!(
                "  pieces to touch: {}/{} cracks in one piece ({:.1}%), {} in two or more, {} joined into another's, {} missed; {} pieces, {} on decoys, {} on neither",
                p.one_piece,
                p.cracks,
                100.0 * p.one_piece_rate,
                p.in_pieces,
                p.joined,
                p.missed,
                p.pieces,
                p.on_decoys,
                p.on_nothing
            );
        }
    }
    Ok(())
}

/// Arguments of `crackbot detector-tradeoff`.
#[derive(Debug, Args)]
pub struct DetectorTradeoffArgs {
    /// COCO ground truth to evaluate on.
    #[arg(long)]
    coco: PathBuf,
    /// Folder the COCO `file_name`s are relative to (default: the COCO file's folder).
    #[arg(long)]
    images: Option<PathBuf>,
    /// ONNX models to compare (default: crack-detector-{256,320,416}.onnx beside the default model).
    #[arg(long, num_args = 1..)]
    models: Vec<PathBuf>,
    /// Leave out the classical baseline.
    #[arg(long)]
    no_classical: bool,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Output folder (tradeoff.md, tradeoff.json, tradeoff.png).
    #[arg(long, default_value = "out/detector-tradeoff")]
    out: PathBuf,
}

/// `crackbot detector-tradeoff`: mAP50 against input size against milliseconds per frame.
pub fn detector_tradeoff(args: DetectorTradeoffArgs) -> Result<()> {
    let bench = Benchmark::load(&args.coco, args.images.as_deref())?;
    let config = TradeoffConfig {
        models: if args.models.is_empty() {
            trained_models()
        } else {
            args.models.clone()
        },
        classical: !args.no_classical,
        threads: args.threads,
    };
    crackbot_plots::load_font()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut bar: Option<ProgressBar> = None;
    let report = tradeoff::detector_tradeoff(
        &bench,
        &config,
        |name, p| {
            let b = bar.get_or_insert_with(|| image_bar(p.total, name, false));
            b.set_position(p.done as u64);
            if p.done == p.total {
                b.finish_and_clear();
                bar = None;
            }
        },
        |r| {
            println!(
                "{}: mAP50 {:.3}, mAP {:.3}, {:.1} ms/frame",
                r.detector, r.map50, r.map, r.ms_per_frame
            );
        },
    )?;
    let (md, md_path, json_path) = report.write(&args.out)?;
    let png = args.out.join("tradeoff.png");
    crackbot_plots::vision::detector_tradeoff_png(&png, &report.rows)?;
    print!("{md}");
    println!(
        "written: {}, {}, {}",
        md_path.display(),
        json_path.display(),
        png.display()
    );
    Ok(())
}
