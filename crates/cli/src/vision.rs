//! `crackbot detect` and `crackbot homography`: the camera half of the inspection, as an operator
//! runs it. The work is `crackbot-vision`'s; this module parses and prints.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use crackbot_vision::detect::{detect_images, DetectConfig, DetectionReport};
use crackbot_vision::fusion::FusionParams;
use crackbot_vision::homography::{read_pairs, HomographyCalibration};
use crackbot_vision::model::{build_detector, DetectorChoice, DetectorKind};
use crackbot_vision::preprocess::PostprocessParams;
use crackbot_vision::Detector;

/// Detector choice shared by `detect` and `eval-detector`.
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
    /// Also report the model's box-head boxes (boxes in the crack photos' own convention, no
    /// centre line, scored under 0.5 below every crack of the crack map; `"source": "box_head"`).
    #[arg(long)]
    box_head: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// `crackbot detect`.
pub fn detect(args: DetectArgs) -> Result<()> {
    if !(0.0..=1.0).contains(&args.threshold) {
        bail!("--threshold must be in [0, 1], got {}", args.threshold);
    }
    let homography = match &args.calibration {
        Some(p) => Some(HomographyCalibration::load(p)?.homography()?),
        None => None,
    };
    let params = PostprocessParams {
        score_threshold: args.threshold,
        box_head: args.box_head,
        ..PostprocessParams::default()
    };
    let mut detector = args.detector.build(params)?;
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
            args.min_frames,
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
    if d.source == crackbot_vision::DetectionSource::BoxHead {
        line += "  (box head: a box only)";
    }
    match (&d.axis_mm, d.length_mm, &d.axis_px) {
        (Some([a, b]), Some(len), _) => {
            line += &format!(
                "  runs ({:.1}, {:.1}) → ({:.1}, {:.1}) mm, {len:.1} mm long",
                a[0], a[1], b[0], b[1]
            );
        }
        (_, _, Some([a, b])) => {
            line += &format!(
                "  runs ({:.0}, {:.0}) → ({:.0}, {:.0}) px",
                a[0], a[1], b[0], b[1]
            );
        }
        _ => {}
    }
    println!("{line}");
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
            let h = cal.homography()?;
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
