//! `crackbot sim …`: the simulator's datasets, calibration, work-precision report and the
//! real-vs-simulated comparison.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use crackbot_recording::Format;
use crackbot_sim::calibrate::calibrate_to_real;
use crackbot_sim::experiment::{generate_dataset, ExperimentConfig};
use crackbot_sim::recordings::{compare_slides, load_recordings, recordings_of_repetition};
use crackbot_sim::work_precision::{default_methods, work_precision};
use indicatif::{ProgressBar, ProgressStyle};

use crate::args::{ExperimentArg, FormatArg};

/// Simulator commands.
#[derive(Debug, Subcommand)]
pub enum SimCommand {
    /// Simulate the paper's experiment and write its recordings (authors' nine columns).
    Dataset(DatasetArgs),
    /// Fit the simulated sensor's optics to real recordings of the recognition experiment.
    Calibrate(CalibrateArgs),
    /// Integrators' error against a fine-step reference vs run time (table, JSON and PNG).
    WorkPrecision(WorkPrecisionArgs),
    /// Real and simulated slides side by side, per class and channel (PNG).
    Compare(CompareArgs),
    /// Camera images of a scene with ground-truth boxes and the exact pixel↔mm homography
    /// (PNG + JSON per frame, and a COCO file for `crackbot eval-detector`).
    Render(RenderArgs),
    /// Crack-detector data: frames of many random scenes with per-pixel crack masks (8-bit PNG,
    /// 255 = crack), a COCO file and every feature's ground truth.
    DetectorSet(DetectorSetArgs),
    /// Check a scene file and summarise it.
    Scene(SceneArgs),
}

/// `crackbot sim render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file (TOML, or JSON when named `.json`); the built-in default scene when left out.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Output folder: images/frame_NNNN.{png,json} and coco.json.
    #[arg(long, default_value = "out/sim-images")]
    out: PathBuf,
    /// Frames to render (lighting and noise change from frame to frame).
    #[arg(long, default_value_t = 4)]
    frames: u32,
    /// Seed of the first frame.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Keep the plate's texture and crack photos across frames (one physical plate).
    #[arg(long)]
    same_plate: bool,
    /// Folder of the real crack photos and masks (default: $CRACKBOT_CRACKS_DIR or
    /// ../shared/data/cracks).
    #[arg(long)]
    cracks: Option<PathBuf>,
}

/// `crackbot sim detector-set`.
#[derive(Debug, Args)]
pub struct DetectorSetArgs {
    /// Random scenes to draw (seeds SEED, SEED + 1, …).
    #[arg(long)]
    scenes: u32,
    /// Frames rendered of each scene (lighting, noise and crack photos change between them).
    #[arg(long, default_value_t = 2)]
    frames_per_scene: u32,
    /// Seed of the first scene.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output folder: images/, masks/, annotations.json and features.json.
    #[arg(long)]
    out: PathBuf,
    /// Random-scene parameters (TOML, the fields of `RandomSceneParams`; defaults when left out).
    #[arg(long)]
    params: Option<PathBuf>,
    /// Folder of the real crack photos and masks (default: $CRACKBOT_CRACKS_DIR or
    /// ../shared/data/cracks).
    #[arg(long)]
    cracks: Option<PathBuf>,
    /// Print the summary as JSON (no progress bar).
    #[arg(long)]
    json: bool,
}

/// `crackbot sim scene`.
#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Scene file (TOML, or JSON when named `.json`); the built-in default scene when left out.
    scene: Option<PathBuf>,
}

/// `crackbot sim dataset`.
#[derive(Debug, Args)]
pub struct DatasetArgs {
    /// Which experiment.
    #[arg(long, value_enum)]
    experiment: ExperimentArg,
    /// Output folder (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// Seed: the same seed writes the same files.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Recordings per surface (the paper: 5).
    #[arg(long, default_value_t = 5)]
    recordings: u32,
    /// Slides per recording (the paper: 12).
    #[arg(long, default_value_t = 12)]
    slides: u32,
    /// File format.
    #[arg(long, value_enum, default_value_t = FormatArg::Csv)]
    format: FormatArg,
    /// Leave out the per-plate mounts fitted to the real recordings (resting-level offsets and
    /// reflectivity of each plate): every plate sits the same.
    #[arg(long)]
    no_plate_mounts: bool,
    /// Leave out the plates' surface roughness.
    #[arg(long)]
    no_roughness: bool,
    /// Sliding speed, mm/s (the paper states about 3.89; the authors' files move at about 4.6).
    #[arg(long, default_value_t = crackbot_sim::experiment::PAPER_SPEED_MM_S)]
    speed_mm_s: f64,
    /// Where the strokes start: MIN,MAX mm before the plate's feature, drawn uniformly for each
    /// recording (default: 6,7.4 for recognition, the real onsets' reading that transfers best;
    /// 5,10 for width, the paper's "approximately 5–10 mm from the crack edge"; MIN = MAX fixes
    /// it). The simulated figures depend on it: `crates/sim/docs/calibration.md`, "Width on six
    /// fresh seeds" and "Where the strokes start, again".
    #[arg(
        long,
        value_name = "MIN,MAX",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    start_mm: Option<Vec<f64>>,
    /// Recognition experiment: add plates with cracks printed on paper, labelled "no crack"
    /// (`crackbot_sim::plates::paper_printed_decoys`: 0.5, 1, 2 and 4 mm lines of four inks;
    /// files `crack_printed_w*_r*`), as the visual-tactile paper's authors recorded theirs. A
    /// parameter file's `[samples] printed_decoys` replaces the set.
    #[arg(long)]
    printed_decoys: bool,
    /// Simulate with these parameters instead of the calibrated ones: a TOML file with any of
    /// the tables `[sensor.finger]`, `[sensor.optics]` (fields of `FingerParams`,
    /// `OpticsParams`) and `[samples]` (fields of `Samples`); what it leaves out stays calibrated.
    #[arg(long)]
    params: Option<PathBuf>,
}

/// `crackbot sim calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Folder of real recognition recordings (e.g. ../shared/data/tactile/type).
    #[arg(long)]
    real: PathBuf,
    /// Folder of real width recordings (e.g. ../shared/data/tactile/width): fits that
    /// experiment's plate mounts too.
    #[arg(long)]
    real_width: Option<PathBuf>,
    /// Use only this repetition (the others stay unseen for checking the transfer).
    #[arg(long, default_value_t = 1)]
    repetition: u32,
    /// Evaluations per Nelder–Mead run of the optics.
    #[arg(long, default_value_t = 300)]
    evaluations: usize,
    /// Mechanics candidates (tip radius, lateral stiffness, friction, crack depth, bump radius
    /// and height) simulated, each with its optics refitted.
    #[arg(long, default_value_t = 60)]
    mechanics_evaluations: usize,
    /// Weight of the tip-speed term (squared RMS distance of the position column's speed
    /// quantiles, (mm/s)²) against the channels' weighted squared quantile distances (counts²).
    /// 0 (the default) leaves it out, as the committed calibration was fitted; 1000 makes a
    /// 1 mm/s RMS miss cost as much as 31.6 counts RMS of P.
    #[arg(long, default_value_t = 0.0)]
    speed_weight: f64,
    /// Take the proximity fibre's dark level from the data (the 0.5 % quantile of every real
    /// proximity reading) instead of fitting it.
    #[arg(long)]
    measured_dark: bool,
    /// Keep the proximity fibre on the far side of its curve's peak (the reading falls as the
    /// surface recedes).
    #[arg(long)]
    far_branch: bool,
    /// Compare the proximity channel at its low tail quantiles too (0.5, 1, 2 %), where the
    /// short dips into the dark over narrow cracks show.
    #[arg(long)]
    p_tails: bool,
    /// Keep the proximity fibre's spot at least this wide, mm (0: no bound).
    #[arg(long, default_value_t = 0.0)]
    min_spot_mm: f64,
    /// Keep these mechanics parameters at the starting values (comma-separated names:
    /// finger.tip_radius_mm, finger.lateral_stiffness_n_mm, finger.friction,
    /// samples.crack_depth_mm, samples.bump_radius_mm, samples.bump_height_mm,
    /// samples.crack_wall_angle_deg).
    #[arg(long, value_delimiter = ',')]
    fixed: Vec<String>,
    /// Start the search from these parameters instead of the calibrated ones: a TOML file as
    /// `sim dataset --params` takes.
    #[arg(long)]
    start: Option<PathBuf>,
    /// Write the report as JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the fitted parameters (finger, optics, plates, mounts) as a TOML file that
    /// `sim dataset --params` and `sim calibrate --start` take.
    #[arg(long)]
    params_out: Option<PathBuf>,
}

/// `crackbot sim work-precision`.
#[derive(Debug, Args)]
pub struct WorkPrecisionArgs {
    /// Output folder for work_precision.{json,png}.
    #[arg(long, default_value = "out/work-precision")]
    out: PathBuf,
}

/// `crackbot sim compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Folder of real recordings.
    #[arg(long)]
    real: PathBuf,
    /// Folder of simulated recordings of the same experiment (`crackbot sim dataset`).
    #[arg(long)]
    sim: PathBuf,
    /// PNG to write.
    #[arg(long, default_value = "out/real-vs-sim.png")]
    out: PathBuf,
    /// Which slide of each recording to draw.
    #[arg(long, default_value_t = 2)]
    slide: u32,
}

pub(crate) fn bar(total: usize, what: &str) -> ProgressBar {
    let bar = if std::env::var_os("CI").is_some() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(total as u64)
    };
    if let Ok(style) =
        ProgressStyle::with_template(&format!("{what} {{bar:30}} {{pos}}/{{len}} {{elapsed}}"))
    {
        bar.set_style(style);
    }
    bar
}

/// Runs a `crackbot sim` command.
pub fn run(cmd: SimCommand) -> Result<()> {
    match cmd {
        SimCommand::Dataset(a) => dataset(a),
        SimCommand::Calibrate(a) => calibrate(a),
        SimCommand::WorkPrecision(a) => work_precision_cmd(a),
        SimCommand::Compare(a) => compare(a),
        SimCommand::Render(a) => render_cmd(a),
        SimCommand::DetectorSet(a) => detector_set_cmd(a),
        SimCommand::Scene(a) => scene_cmd(a),
    }
}

fn dataset(a: DatasetArgs) -> Result<()> {
    let mut config = ExperimentConfig::paper(a.experiment.into(), a.seed);
    config.recordings = a.recordings;
    config.slides = a.slides;
    if a.no_plate_mounts {
        config.mounts.clear();
    }
    if a.no_roughness {
        config.samples.roughness_rms_mm = 0.0;
    }
    if !(a.speed_mm_s.is_finite() && a.speed_mm_s > 0.0) {
        bail!(
            "--speed-mm-s must be a positive speed, got {}",
            a.speed_mm_s
        );
    }
    config.speed_mm_s = a.speed_mm_s;
    if let Some(range) = &a.start_mm {
        let &[lo, hi] = range.as_slice() else {
            bail!("--start-mm takes two distances, MIN,MAX mm, got {range:?}");
        };
        if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
            bail!("--start-mm must be 0 ≤ MIN ≤ MAX mm, got {lo},{hi}");
        }
        config.start_range_mm = (lo, hi);
    }
    if a.printed_decoys {
        if !matches!(a.experiment, ExperimentArg::Recognition) {
            bail!("--printed-decoys adds plates to --experiment recognition only");
        }
        config.samples.printed_decoys = crackbot_sim::plates::paper_printed_decoys();
    }
    if let Some(path) = &a.params {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        config
            .apply_params_toml(&text)
            .with_context(|| format!("parameters of {}", path.display()))?;
    }
    let total = config.surfaces().len() * a.recordings as usize;
    let pb = bar(total, "simulating");
    let report = generate_dataset(
        &config,
        &a.out,
        Format::from(a.format).extension(),
        |done, _| pb.set_position(done as u64),
    )
    .with_context(|| format!("simulating into {}", a.out.display()))?;
    pb.finish_and_clear();
    println!(
        "wrote {} recordings ({} rows, {:.0} simulated s) to {} in {:.1} s ({:.0}× real time)",
        report.recordings,
        report.rows,
        report.simulated_s,
        report.out.display(),
        report.wall_s,
        report.real_time_factor
    );
    Ok(())
}

fn calibrate(a: CalibrateArgs) -> Result<()> {
    let real = recordings_of_repetition(&a.real, a.repetition)?;
    let width_real = match &a.real_width {
        Some(dir) => Some(recordings_of_repetition(dir, a.repetition)?),
        None => None,
    };
    let pb = bar(
        a.mechanics_evaluations,
        "fitting mechanics, geometry and optics",
    );
    let mut start = crackbot_sim::calibrate::starting_config();
    if let Some(path) = &a.start {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        start
            .apply_params_toml(&text)
            .with_context(|| format!("{}", path.display()))?;
    }
    let summary = calibrate_to_real(
        &start,
        &real,
        width_real.as_deref(),
        &crackbot_sim::calibrate::SearchSettings {
            evaluations: a.evaluations,
            mechanics_evaluations: a.mechanics_evaluations,
            speed_weight: a.speed_weight,
            fixed: a.fixed.clone(),
            proximity: crackbot_sim::calibrate::ProximityRules {
                measured_dark: a.measured_dark,
                far_branch: a.far_branch,
                tails: a.p_tails,
                min_spot_mm: a.min_spot_mm,
            },
        },
        |k, _| pb.set_position(k as u64),
    )?;
    pb.finish_and_clear();
    let report = &summary.report;
    println!("quantile distance (RMS counts)   D1      D2      D3      P");
    println!(
        "before (uncalibrated)        {:7.2} {:7.2} {:7.2} {:7.2}",
        report.rms_before[0], report.rms_before[1], report.rms_before[2], report.rms_before[3]
    );
    println!(
        "after                        {:7.2} {:7.2} {:7.2} {:7.2}",
        report.rms_after[0], report.rms_after[1], report.rms_after[2], report.rms_after[3]
    );
    println!(
        "tip speed quantile distance (RMS mm/s): before {:.2}, after {:.2}",
        report.speed_rms_before, report.speed_rms_after
    );
    println!("fitted finger (TOML, [sensor.finger]):");
    println!("{}", toml::to_string(&report.finger)?);
    println!("fitted plates (TOML, [samples]):");
    println!("{}", toml::to_string(&report.samples)?);
    println!("fitted optics (TOML, [sensor.optics]):");
    println!("{}", toml::to_string(&report.optics)?);
    for (name, m) in &summary.mounts {
        println!("plate mounts, {name} (D1, D2, D3 offsets in counts; reflectivity):");
        for x in m {
            println!(
                "  [{:.2}, {:.2}, {:.2}], {:.4}",
                x.offset_counts[0], x.offset_counts[1], x.offset_counts[2], x.reflectivity
            );
        }
    }
    if let Some(path) = &a.params_out {
        let mut finger_optics = toml::Table::new();
        finger_optics.insert("finger".into(), toml::Value::try_from(&report.finger)?);
        finger_optics.insert("optics".into(), toml::Value::try_from(&report.optics)?);
        let mut mounts = toml::Table::new();
        for (name, m) in &summary.mounts {
            mounts.insert(name.clone(), toml::Value::try_from(m)?);
        }
        let mut doc = toml::Table::new();
        doc.insert("sensor".into(), toml::Value::Table(finger_optics));
        doc.insert("samples".into(), toml::Value::try_from(&report.samples)?);
        doc.insert("mounts".into(), toml::Value::Table(mounts));
        std::fs::write(path, toml::to_string(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("wrote the fitted parameters to {}", path.display());
    }
    if let Some(path) = a.json {
        let doc = serde_json::to_value(&summary)?;
        std::fs::write(&path, serde_json::to_string_pretty(&doc)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn work_precision_cmd(a: WorkPrecisionArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let methods = default_methods();
    let pb = bar(methods.len(), "integrating");
    let rows = work_precision(&methods, |d, _| pb.set_position(d as u64))?;
    pb.finish_and_clear();
    println!(
        "{:<26} {:>12} {:>12} {:>12} {:>10}",
        "method", "RMS counts", "max counts", "ms / sim s", "× real"
    );
    for r in &rows {
        let fmt = |v: Option<f64>| v.map_or("failed".to_string(), |v| format!("{v:.2e}"));
        println!(
            "{:<26} {:>12} {:>12} {:>12.2} {:>10.0}{}",
            r.method,
            fmt(r.rms_error_counts),
            fmt(r.max_error_counts),
            r.ms_per_sim_second,
            r.real_time_factor,
            r.failure
                .as_deref()
                .map(|f| format!("  ({f})"))
                .unwrap_or_default()
        );
    }
    let json = a.out.join("work_precision.json");
    std::fs::write(&json, serde_json::to_string_pretty(&rows)?)
        .with_context(|| format!("writing {}", json.display()))?;
    let png = a.out.join("work_precision.png");
    crackbot_plots::sim::work_precision_png(&png, &rows)?;
    println!("wrote {} and {}", json.display(), png.display());
    Ok(())
}

fn compare(a: CompareArgs) -> Result<()> {
    crackbot_plots::load_font()?;
    let real = load_recordings(&a.real)?;
    let sim = load_recordings(&a.sim)?;
    let comparison = compare_slides(&real, &sim, a.slide);
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    crackbot_plots::sim::compare_png(&a.out, &comparison)?;
    println!("wrote {}", a.out.display());
    Ok(())
}

fn scene_cmd(a: SceneArgs) -> Result<()> {
    let summary = crackbot_sim::Scene::load_or_default(a.scene.as_deref())?.summary();
    let name = if summary.name.is_empty() {
        "(unnamed)"
    } else {
        &summary.name
    };
    println!(
        "scene {name}: plate {} × {} mm ({}), {} features",
        summary.plate_size_mm[0],
        summary.plate_size_mm[1],
        summary.material,
        summary.features.len()
    );
    for f in &summary.features {
        println!(
            "  features[{}] {:<6} x {:.1}..{:.1} mm, y {:.1}..{:.1} mm",
            f.index, f.kind, f.min_mm[0], f.max_mm[0], f.min_mm[1], f.max_mm[1]
        );
    }
    match &summary.camera {
        Some(c) => println!(
            "camera {}×{} px at ({}, {}, {}) mm looking at ({}, {}) mm",
            c.resolution[0],
            c.resolution[1],
            c.position_mm[0],
            c.position_mm[1],
            c.position_mm[2],
            c.look_at_mm[0],
            c.look_at_mm[1]
        ),
        None => println!("no camera (tactile only)"),
    }
    println!("valid");
    Ok(())
}

fn render_cmd(a: RenderArgs) -> Result<()> {
    use crackbot_sim::render::{render_dataset, CrackAssets, RenderOptions};
    let scene = crackbot_sim::Scene::load_or_default(a.scene.as_deref())?;
    if scene.camera.is_none() {
        bail!("the scene has no camera: nothing to render (add a [camera] table)");
    }
    if a.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let assets = match &a.cracks {
        Some(dir) => CrackAssets::load(dir)?,
        None => CrackAssets::load_default()?,
    };
    let options = RenderOptions {
        appearance_seed: a.same_plate.then_some(a.seed),
        ..RenderOptions::default()
    };
    let pb = bar(a.frames as usize, "rendering");
    let summary = render_dataset(
        &scene,
        &assets,
        &options,
        a.frames,
        a.seed,
        &a.out,
        |done, _| pb.set_position(done as u64),
    )?;
    pb.finish_and_clear();
    println!(
        "rendered {} frames ({:.0} ms each), {} ground-truth boxes; wrote {} (images in {})",
        summary.frames,
        summary.ms_per_frame,
        summary.boxes,
        summary.coco.display(),
        summary.images.display()
    );
    Ok(())
}

fn detector_set_cmd(a: DetectorSetArgs) -> Result<()> {
    use crackbot_sim::render::{write_detector_set, CrackAssets};
    use crackbot_sim::RandomSceneParams;
    if a.scenes == 0 {
        bail!("--scenes must be at least 1");
    }
    if a.frames_per_scene == 0 {
        bail!("--frames-per-scene must be at least 1");
    }
    let params = match &a.params {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("reading {}", path.display()))?;
            toml::from_str::<RandomSceneParams>(&text)
                .with_context(|| format!("parsing random-scene parameters {}", path.display()))?
        }
        None => RandomSceneParams::default(),
    };
    params.validate()?;
    let assets = match &a.cracks {
        Some(dir) => CrackAssets::load(dir)?,
        None => CrackAssets::load_default()?,
    };
    let total = a.scenes as usize * a.frames_per_scene as usize;
    let pb = if a.json {
        ProgressBar::hidden()
    } else {
        bar(total, "rendering")
    };
    let summary = write_detector_set(
        &params,
        &assets,
        a.scenes,
        a.frames_per_scene,
        a.seed,
        &a.out,
        |done, _| pb.set_position(done as u64),
    )
    .with_context(|| format!("writing the detector set to {}", a.out.display()))?;
    pb.finish_and_clear();
    if a.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "rendered {} frames of {} random scenes ({:.0} ms each): {} cracks, {} decoys, {} screws in view",
            summary.frames,
            summary.scenes,
            summary.ms_per_frame,
            summary.cracks,
            summary.decoys,
            summary.screws
        );
        println!(
            "wrote {} images, {} crack masks (8-bit, 255 = crack), {} and {}",
            summary.images.display(),
            summary.masks.display(),
            summary.annotations.display(),
            summary.features.display()
        );
    }
    Ok(())
}
