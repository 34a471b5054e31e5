//! `crackbot detect` and `crackbot eval-detector`: the camera half of the inspection.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use crackbot_vision::classical::{ClassicalDetector, ClassicalParams};
use crackbot_vision::coco::{detect_dataset, evaluate, save_results, CocoDataset};
use crackbot_vision::fusion::{fuse, FusionParams};
use crackbot_vision::homography::HomographyCalibration;
use crackbot_vision::onnx::OnnxDetector;
use crackbot_vision::preprocess::PostprocessParams;
use crackbot_vision::{Detection, Detector};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

/// The default model, relative to the repository root.
const DEFAULT_MODEL: &str = "models/detector/crack-detector-320.onnx";

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

fn model_path(arg: &Option<PathBuf>) -> PathBuf {
    if let Some(p) = arg {
        return p.clone();
    }
    let here = PathBuf::from(DEFAULT_MODEL);
    if here.is_file() {
        return here;
    }
    // A binary built from this repository also finds the model from elsewhere.
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(DEFAULT_MODEL)
}

fn build_detector(args: &DetectorArgs, params: PostprocessParams) -> Result<Box<dyn Detector>> {
    Ok(match args.detector {
        DetectorArg::Onnx => {
            let path = model_path(&args.model);
            Box::new(
                OnnxDetector::load(&path, params, args.threads)
                    .with_context(|| format!("loading the detector {}", path.display()))?,
            )
        }
        DetectorArg::Classical => Box::new(ClassicalDetector::new(ClassicalParams::default())?),
    })
}

fn read_rgb(path: &Path) -> Result<image::RgbImage> {
    Ok(image::open(path)
        .with_context(|| format!("reading image {}", path.display()))?
        .to_rgb8())
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
    let mut frames = Vec::new();
    for path in &args.images {
        let rgb = read_rgb(path)?;
        let started = Instant::now();
        let mut found = detector
            .detect(&rgb)
            .with_context(|| format!("detecting in {}", path.display()))?;
        let ms = started.elapsed().as_secs_f64() * 1e3;
        found.retain(|d| d.score >= args.threshold);
        frames.push((path.clone(), rgb, found, ms));
    }
    // A centre the homography cannot map (behind the camera's horizon) has no surface position.
    let to_mm = |d: &Detection| -> Option<[f64; 2]> {
        let (cx, cy) = d.bbox.centre();
        homography
            .as_ref()
            .and_then(|h| h.pixel_to_surface([f64::from(cx), f64::from(cy)]).ok())
    };
    let detection_json = |d: &Detection, extra: serde_json::Value| {
        let mut v = json!({
            "bbox": [d.bbox.x0, d.bbox.y0, d.bbox.x1, d.bbox.y1],
            "score": d.score,
        });
        if let Some(mm) = to_mm(d) {
            v["centre_mm"] = json!(mm);
        }
        if let (Some(obj), Some(e)) = (v.as_object_mut(), extra.as_object()) {
            obj.extend(e.clone());
        }
        v
    };
    let fused = args.fuse.then(|| {
        let dets: Vec<Vec<Detection>> = frames.iter().map(|f| f.2.clone()).collect();
        fuse(
            &dets,
            &FusionParams {
                min_frames: args.min_frames,
                ..FusionParams::default()
            },
        )
    });
    if let Some(dir) = &args.annotate {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (path, rgb, found, _) in &frames {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
            let out = dir.join(format!("{stem}-detections.png"));
            let mut canvas = rgb.clone();
            for d in found {
                draw_box(&mut canvas, d, [255, 40, 40]);
            }
            if let Some(fused) = &fused {
                for f in fused {
                    draw_box(&mut canvas, &f.detection, [40, 220, 255]);
                }
            }
            canvas
                .save(&out)
                .with_context(|| format!("writing {}", out.display()))?;
            if !args.json {
                println!("annotated: {}", out.display());
            }
        }
    }
    if args.json {
        let images: Vec<_> = frames
            .iter()
            .map(|(path, rgb, found, ms)| {
                json!({
                    "file": path.display().to_string(),
                    "width": rgb.width(),
                    "height": rgb.height(),
                    "ms": ms,
                    "detections": found.iter().map(|d| detection_json(d, json!({}))).collect::<Vec<_>>(),
                })
            })
            .collect();
        let mut out =
            json!({ "detector": detector.name(), "threshold": args.threshold, "images": images });
        if let Some(fused) = &fused {
            out["fused"] = fused
                .iter()
                .map(|f| detection_json(&f.detection, json!({ "frames_seen": f.frames_seen })))
                .collect();
        }
        println!("{out}");
        return Ok(());
    }
    println!("detector {}, threshold {}", detector.name(), args.threshold);
    for (path, rgb, found, ms) in &frames {
        println!(
            "{} ({}×{}, {ms:.1} ms): {} crack(s)",
            path.display(),
            rgb.width(),
            rgb.height(),
            found.len()
        );
        for d in found {
            print_detection(d, to_mm(d), None);
        }
    }
    if let Some(fused) = &fused {
        println!(
            "fused over {} frames (seen in at least {}): {} crack(s)",
            frames.len(),
            args.min_frames,
            fused.len()
        );
        for f in fused {
            print_detection(&f.detection, to_mm(&f.detection), Some(f.frames_seen));
        }
    }
    Ok(())
}

fn print_detection(d: &Detection, mm: Option<[f64; 2]>, seen: Option<usize>) {
    let b = d.bbox;
    let mut line = format!(
        "  score {:.3}  box x {:.1}–{:.1}, y {:.1}–{:.1} px",
        d.score, b.x0, b.x1, b.y0, b.y1
    );
    if let Some([x, y]) = mm {
        line += &format!("  centre ({x:.1}, {y:.1}) mm");
    }
    if let Some(n) = seen {
        line += &format!("  in {n} frames");
    }
    println!("{line}");
}

/// Draws a 3-pixel rectangle outline.
fn draw_box(img: &mut image::RgbImage, d: &Detection, colour: [u8; 3]) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    if w == 0 || h == 0 || !d.bbox.is_finite() {
        return;
    }
    let clamp = |v: f32, hi: i64| (v.round() as i64).clamp(0, hi - 1);
    let (x0, x1) = (clamp(d.bbox.x0, w), clamp(d.bbox.x1, w));
    let (y0, y1) = (clamp(d.bbox.y0, h), clamp(d.bbox.y1, h));
    for t in 0..3 {
        for x in x0..=x1 {
            for y in [y0 + t, y1 - t] {
                if (0..h).contains(&y) {
                    img.put_pixel(x as u32, y as u32, image::Rgb(colour));
                }
            }
        }
        for y in y0..=y1 {
            for x in [x0 + t, x1 - t] {
                if (0..w).contains(&x) {
                    img.put_pixel(x as u32, y as u32, image::Rgb(colour));
                }
            }
        }
    }
}

/// Times every `detect` call of the detector it wraps.
struct Timed<'a> {
    inner: &'a mut dyn Detector,
    ms: Vec<f64>,
}

impl Detector for Timed<'_> {
    fn name(&self) -> String {
        self.inner.name()
    }
    fn detect(
        &mut self,
        image: &image::RgbImage,
    ) -> std::result::Result<Vec<Detection>, crackbot_vision::VisionError> {
        let started = Instant::now();
        let out = self.inner.detect(image);
        self.ms.push(started.elapsed().as_secs_f64() * 1e3);
        out
    }
}

/// A COCO ground truth, the folder of its images and the category to report.
struct Benchmark {
    gt: CocoDataset,
    root: PathBuf,
    category: u64,
}

impl Benchmark {
    fn load(coco: &Path, images: &Option<PathBuf>) -> Result<Self> {
        let gt = CocoDataset::load(coco)?;
        let root = match images {
            Some(d) => d.clone(),
            None => coco
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from(".")),
        };
        let category = match gt.categories.as_slice() {
            [one] => one.id,
            [] => bail!("{}: no categories", coco.display()),
            many => many
                .iter()
                .find(|c| c.name == "crack")
                .map(|c| c.id)
                .with_context(|| {
                    format!(
                        "{}: several categories and none named `crack`",
                        coco.display()
                    )
                })?,
        };
        Ok(Self { gt, root, category })
    }

    /// Runs `detector` over every image with a progress bar (hidden when `quiet`): the results,
    /// their metrics and the median milliseconds of one `detect` call (decoding excluded).
    fn run(
        &self,
        detector: &mut dyn Detector,
        quiet: bool,
    ) -> Result<(
        Vec<crackbot_vision::coco::CocoResult>,
        crackbot_vision::coco::CocoMetrics,
        f64,
    )> {
        let bar = if quiet {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(self.gt.images.len() as u64).with_style(
                ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} images, {eta} left")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            )
        };
        bar.set_message(detector.name());
        let mut timed = Timed {
            inner: detector,
            ms: Vec::new(),
        };
        let results = detect_dataset(&mut timed, &self.gt, &self.root, self.category, |p| {
            bar.set_position(p.done as u64)
        })?;
        bar.finish_and_clear();
        let metrics = evaluate(&self.gt, &results)?;
        let mut ms = timed.ms;
        ms.sort_by(f64::total_cmp);
        let median = ms.get(ms.len() / 2).copied().unwrap_or(f64::NAN);
        Ok((results, metrics, median))
    }
}

/// Post-processing for mAP: every candidate down to 0.001, as COCO evaluations do.
fn map_params() -> PostprocessParams {
    PostprocessParams {
        score_threshold: 0.001,
        ..PostprocessParams::default()
    }
}

/// `crackbot eval-detector`.
pub fn eval_detector(args: EvalDetectorArgs) -> Result<()> {
    let bench = Benchmark::load(&args.coco, &args.images)?;
    let gt = &bench.gt;
    let mut detector = build_detector(&args.detector, map_params())?;
    let (results, metrics, ms_per_image) = bench.run(detector.as_mut(), args.json)?;
    if let Some(path) = &args.save_results {
        save_results(path, &results)?;
    }
    if args.json {
        let mut out = serde_json::to_value(metrics)?;
        out["detector"] = json!(detector.name());
        out["coco"] = json!(args.coco.display().to_string());
        out["images"] = json!(gt.images.len());
        out["ground_truth_boxes"] = json!(gt.annotations.len());
        out["detections"] = json!(results.len());
        out["ms_per_image"] = json!(ms_per_image);
        out["ms_per_image_is"] = json!("median of one detect call, image decoding excluded");
        println!("{out}");
        return Ok(());
    }
    println!(
        "{} on {} ({} images, {} boxes): {} detections, median {ms_per_image:.1} ms per image",
        detector.name(),
        args.coco.display(),
        gt.images.len(),
        gt.annotations.len(),
        results.len()
    );
    for (name, v) in crackbot_vision::coco::CocoMetrics::NAMES
        .iter()
        .zip(metrics.stats())
    {
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

/// One row of the detector trade-off.
#[derive(Debug, serde::Serialize)]
struct TradeoffRow {
    detector: String,
    input_size: Option<usize>,
    map: f64,
    map50: f64,
    ar100: f64,
    ms_per_frame: f64,
}

/// `crackbot detector-tradeoff`: mAP50 against input size against milliseconds per frame.
pub fn detector_tradeoff(args: DetectorTradeoffArgs) -> Result<()> {
    let bench = Benchmark::load(&args.coco, &args.images)?;
    let models: Vec<PathBuf> = if args.models.is_empty() {
        [256, 320, 416]
            .iter()
            .map(|s| model_path(&None).with_file_name(format!("crack-detector-{s}.onnx")))
            .collect()
    } else {
        args.models.clone()
    };
    crackbot_plots::load_font()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut rows = Vec::new();
    for m in &models {
        let mut d = OnnxDetector::load(m, map_params(), args.threads)
            .with_context(|| format!("loading {}", m.display()))?;
        let size = d.input_size();
        let (_, metrics, ms) = bench.run(&mut d, false)?;
        println!(
            "{}: mAP50 {:.3}, mAP {:.3}, {ms:.1} ms/frame",
            d.name(),
            metrics.map50,
            metrics.map
        );
        rows.push(TradeoffRow {
            detector: d.name(),
            input_size: Some(size),
            map: metrics.map,
            map50: metrics.map50,
            ar100: metrics.ar100,
            ms_per_frame: ms,
        });
    }
    if !args.no_classical {
        let mut d = ClassicalDetector::new(ClassicalParams::default())?;
        let (_, metrics, ms) = bench.run(&mut d, false)?;
        println!(
            "classical: mAP50 {:.3}, mAP {:.3}, {ms:.1} ms/frame",
            metrics.map50, metrics.map
        );
        rows.push(TradeoffRow {
            detector: d.name(),
            input_size: None,
            map: metrics.map,
            map50: metrics.map50,
            ar100: metrics.ar100,
            ms_per_frame: ms,
        });
    }
    let mut md = format!(
        "# Crack detector: accuracy against run time (`crackbot detector-tradeoff`)\n\n\
         On {} ({} images, {} boxes); {} ONNX Runtime thread(s); ms = median of one `detect` call \
         (letterbox + model + NMS), image decoding excluded.\n\n\
         | detector | input | mAP@0.5 | mAP@[.5:.95] | AR@100 | ms/frame |\n|---|---|---|---|---|---|\n",
        args.coco.display(),
        bench.gt.images.len(),
        bench.gt.annotations.len(),
        args.threads
    );
    for r in &rows {
        md += &format!(
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.1} |\n",
            r.detector,
            r.input_size.map_or("–".to_string(), |s| format!("{s}×{s}")),
            r.map50,
            r.map,
            r.ar100,
            r.ms_per_frame
        );
    }
    md += "\n![mAP50 against ms per frame](tradeoff.png)\n";
    let md_path = args.out.join("tradeoff.md");
    std::fs::write(&md_path, &md).with_context(|| format!("writing {}", md_path.display()))?;
    let json_path = args.out.join("tradeoff.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&rows)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    let png = args.out.join("tradeoff.png");
    tradeoff_png(&png, &rows).with_context(|| format!("drawing {}", png.display()))?;
    print!("{md}");
    println!(
        "written: {}, {}, {}",
        md_path.display(),
        json_path.display(),
        png.display()
    );
    Ok(())
}

fn tradeoff_png(path: &Path, rows: &[TradeoffRow]) -> Result<()> {
    use plotters::prelude::*;
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
    let x_max = rows
        .iter()
        .map(|r| r.ms_per_frame)
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max)
        * 1.2;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Crack detector: mAP@0.5 against ms per frame",
            ("sans-serif", 24),
        )
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..x_max, 0f64..1f64)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("ms per frame (one core)")
        .y_desc("mAP@0.5")
        .label_style(("sans-serif", 16))
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let onnx: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.input_size.is_some())
        .map(|r| (r.ms_per_frame, r.map50))
        .collect();
    chart
        .draw_series(LineSeries::new(onnx.clone(), BLUE.stroke_width(2)))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    for r in rows {
        let colour = if r.input_size.is_some() { BLUE } else { RED };
        let label = r
            .input_size
            .map_or(r.detector.clone(), |s| format!("{s}×{s}"));
        chart
            .draw_series(std::iter::once(Circle::new(
                (r.ms_per_frame, r.map50),
                6,
                colour.filled(),
            )))
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .draw_series(std::iter::once(Text::new(
                label,
                (r.ms_per_frame, r.map50 + 0.03),
                ("sans-serif", 16),
            )))
            .map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
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

fn read_pairs(path: &Path) -> Result<Vec<crackbot_vision::homography::PointPair>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut pairs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let nums: std::result::Result<Vec<f64>, _> =
            fields.iter().map(|f| f.parse::<f64>()).collect();
        match nums {
            Ok(n) if n.len() == 4 => pairs.push(crackbot_vision::homography::PointPair::new(
                [n[0], n[1]],
                [n[2], n[3]],
            )),
            Err(_) if i == 0 => continue, // header
            _ => bail!(
                "{} line {}: expected 4 numbers u,v,x_mm,y_mm, got {line:?}",
                path.display(),
                i + 1
            ),
        }
    }
    Ok(pairs)
}

/// `crackbot homography`.
pub fn homography(cmd: HomographyCommand) -> Result<()> {
    use crackbot_vision::homography::{fit_dlt, fit_ransac};
    match cmd {
        HomographyCommand::Fit {
            pairs,
            out,
            ransac_mm,
            iterations,
            seed,
        } => {
            let all = read_pairs(&pairs)?;
            let (h, kept) = match ransac_mm {
                Some(t) => {
                    let fit = fit_ransac(&all, t, iterations, seed)
                        .with_context(|| format!("fitting {}", pairs.display()))?;
                    let kept: Vec<_> = all
                        .iter()
                        .zip(&fit.inliers)
                        .filter(|(_, &i)| i)
                        .map(|(p, _)| *p)
                        .collect();
                    println!(
                        "RANSAC ({t} mm): {} of {} pairs are inliers",
                        kept.len(),
                        all.len()
                    );
                    (fit.homography, kept)
                }
                None => (
                    fit_dlt(&all).with_context(|| format!("fitting {}", pairs.display()))?,
                    all,
                ),
            };
            let cal = HomographyCalibration::new(&h, kept);
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
