//! `crackbot detect` and `crackbot eval-detector`: the camera half of the inspection.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use crackbot_vision::benchmark::{map_params, Benchmark, EvalReport};
use crackbot_vision::classical::{ClassicalDetector, ClassicalParams};
use crackbot_vision::coco::{save_results, CocoMetrics};
use crackbot_vision::detect::{detect_images, DetectConfig, DetectionReport};
use crackbot_vision::fusion::FusionParams;
use crackbot_vision::homography::{read_pairs, HomographyCalibration};
use crackbot_vision::model::{resolve_model, trained_models};
use crackbot_vision::onnx::OnnxDetector;
use crackbot_vision::preprocess::PostprocessParams;
use crackbot_vision::tradeoff::{self, TradeoffConfig};
use crackbot_vision::Detector;
use indicatif::{ProgressBar, ProgressStyle};

/// Which detector to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DetectorArg {
    /// The trained model (ONNX Runtime).
    Onnx,
    /// The edge-based baseline (no model).
    Classical,
}

/// Detector choice shared by `detect` and `eval-detector`.
#[derive(Debug, Args)]
pub struct DetectorArgs {
    /// Detector.
    #[arg(long, value_enum, default_value_t = DetectorArg::Onnx)]
    detector: DetectorArg,
    /// ONNX model (default: models/detector/crack-detector-320.onnx of this repository).
    #[arg(long)]
    model: Option<PathBuf>,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = 1)]
    threads: usize,
}

/// Arguments of `crackbot detect`.
#[derive(Debug, Args)]
pub struct DetectArgs {
    /// Images (PNG or JPEG).
    #[arg(required = true)]
    images: Vec<PathBuf>,
    #[command(flatten)]
    detector: DetectorArgs,
    /// Minimum score of a reported crack.
    #[arg(long, default_value_t = 0.25)]
    threshold: f32,
    /// Pixel → surface calibration (TOML, see `crackbot_vision::homography`): adds surface
    /// coordinates in mm.
    #[arg(long)]
    calibration: Option<PathBuf>,
    /// Treat the images as frames of one view and fuse their detections.
    #[arg(long)]
    fuse: bool,
    /// With --fuse: frames a crack must be seen in.
    #[arg(long, default_value_t = 2)]
    min_frames: usize,
    /// Write `<image stem>-detections.png` with the boxes drawn into this folder.
    #[arg(long)]
    annotate: Option<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
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

fn build_detector(args: &DetectorArgs, params: PostprocessParams) -> Result<Box<dyn Detector>> {
    Ok(match args.detector {
        DetectorArg::Onnx => {
            let path = resolve_model(args.model.as_deref());
            Box::new(
                OnnxDetector::load(&path, params, args.threads)
                    .with_context(|| format!("loading the detector {}", path.display()))?,
            )
        }
        DetectorArg::Classical => Box::new(ClassicalDetector::new(ClassicalParams::default())?),
    })
}

/// `crackbot detect`.
pub fn detect(args: DetectArgs) -> Result<()> {
    if !(0.0..=1.0).contains(&args.threshold) {
        bail!("--threshold must be in [0, 1], got {}", args.threshold);
    }
    let homography = match &args.calibration {
        Some(p) => Some(HomographyCalibration::load(p)?.validate(p)?),
        None => None,
    };
    let params = PostprocessParams {
        score_threshold: args.threshold,
        ..PostprocessParams::default()
    };
    let mut detector = build_detector(&args.detector, params)?;
    let config = DetectConfig {
        threshold: args.threshold,
        homography,
        fuse: args.fuse.then(|| FusionParams {
            min_frames: args.min_frames,
            ..FusionParams::default()
        }),
        annotate: args.annotate.clone(),
    };
    let report = detect_images(detector.as_mut(), &args.images, &config)?;
    if args.json {
        println!("{}", serde_json::to_value(&report)?);
        return Ok(());
    }
    for out in &report.annotated {
        println!("annotated: {}", out.display());
    }
    println!(
        "detector {}, threshold {}",
        report.detector, report.threshold
    );
    for image in &report.images {
        println!(
            "{} ({}×{}, {:.1} ms): {} crack(s)",
            image.file,
            image.width,
            image.height,
            image.ms,
            image.detections.len()
        );
        for d in &image.detections {
            print_detection(d);
        }
    }
    if let Some(fused) = &report.fused {
        println!(
            "fused over {} frames (seen in at least {}): {} crack(s)",
            report.images.len(),
            report.min_frames.unwrap_or(args.min_frames),
            fused.len()
        );
        for d in fused {
            print_detection(d);
        }
    }
    Ok(())
}

fn print_detection(d: &DetectionReport) {
    let [x0, y0, x1, y1] = d.bbox;
    let mut line = format!(
        "  score {:.3}  box x {x0:.1}–{x1:.1}, y {y0:.1}–{y1:.1} px",
        d.score
    );
    if let Some([x, y]) = d.centre_mm {
        line += &format!("  centre ({x:.1}, {y:.1}) mm");
    }
    if let Some(n) = d.frames_seen {
        line += &format!("  in {n} frames");
    }
    println!("{line}");
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
    let mut detector = build_detector(&args.detector, map_params())?;
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
    /// ONNX models to compare (default: crack-detector-{256,320,416}.onnx in models/detector/).
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
            )
        },
    )?;
    let (md_path, json_path) = report.write(&args.out)?;
    let png = args.out.join("tradeoff.png");
    crackbot_plots::vision::detector_tradeoff_png(&png, &report.rows)?;
    print!("{}", report.markdown());
    println!(
        "written: {}, {}, {}",
        md_path.display(),
        json_path.display(),
        png.display()
    );
    Ok(())
}

/// `crackbot homography …`.
#[derive(Debug, clap::Subcommand)]
pub enum HomographyCommand {
    /// Fit a pixel → surface calibration from point pairs (CSV `u,v,x_mm,y_mm`, header optional).
    Fit {
        /// Point pairs: pixel column u, pixel row v, surface x and y in mm, one pair per line.
        pairs: PathBuf,
        /// Calibration file to write (TOML).
        #[arg(long)]
        out: PathBuf,
        /// Reject outlier pairs by RANSAC with this surface-side threshold in mm.
        #[arg(long)]
        ransac_mm: Option<f64>,
        /// RANSAC iterations.
        #[arg(long, default_value_t = 2000)]
        iterations: usize,
        /// RANSAC seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Validate a calibration file and map pixels through it.
    Check {
        /// Calibration file (TOML).
        file: PathBuf,
        /// Pixels to map, as `u,v` (repeatable).
        #[arg(long = "pixel", value_parser = parse_point)]
        pixels: Vec<[f64; 2]>,
    },
}

fn parse_point(s: &str) -> std::result::Result<[f64; 2], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("{s:?}: {e}")))
        .collect::<std::result::Result<_, _>>()?;
    match v.as_slice() {
        [u, v] => Ok([*u, *v]),
        _ => Err(format!("{s:?}: expected two numbers u,v")),
    }
}

/// `crackbot homography`.
pub fn homography(cmd: HomographyCommand) -> Result<()> {
    use crackbot_vision::homography::{fit_calibration, RansacSettings};
    match cmd {
        HomographyCommand::Fit {
            pairs,
            out,
            ransac_mm,
            iterations,
            seed,
        } => {
            let settings = ransac_mm.map(|threshold_mm| RansacSettings {
                threshold_mm,
                iterations,
                seed,
            });
            let fit = fit_calibration(read_pairs(&pairs)?, settings)
                .with_context(|| format!("fitting {}", pairs.display()))?;
            if let Some(r) = fit.ransac {
                println!(
                    "RANSAC ({} mm): {} of {} pairs are inliers",
                    r.threshold_mm,
                    fit.calibration.pairs.len(),
                    fit.pairs_given
                );
            }
            let cal = fit.calibration;
            cal.save(&out)?;
            println!(
                "{}: {} pairs, reprojection error RMS {:.3} mm (max {:.3}), {:.3} px (max {:.3})",
                out.display(),
                cal.pairs.len(),
                cal.rms_mm,
                cal.max_mm,
                cal.rms_px,
                cal.max_px
            );
        }
        HomographyCommand::Check { file, pixels } => {
            let cal = HomographyCalibration::load(&file)?;
            let h = cal.validate(&file)?;
            println!(
                "{}: {} pairs, reprojection error RMS {:.3} mm (max {:.3}): OK",
                file.display(),
                cal.pairs.len(),
                cal.rms_mm,
                cal.max_mm
            );
            for p in pixels {
                let s = h.pixel_to_surface(p)?;
                println!(
                    "  pixel ({}, {}) → ({:.3}, {:.3}) mm",
                    p[0], p[1], s[0], s[1]
                );
            }
        }
    }
    Ok(())
}
