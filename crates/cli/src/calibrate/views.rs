//! `crackbot calibrate views` (simulator): the target seen through a scene's camera, its lens
//! included, at the poses of a calibration session, and laid centred on the plate as seen from
//! the scene's camera: the images `camera` and `surface` take on a real bench.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use crackbot_calib_target::TargetSpec;
use crackbot_sim::camera::Camera;
use crackbot_sim::render::{calibration_poses, render_sheet, SheetOptions};
use crackbot_sim::Scene;
use indicatif::ProgressBar;

use super::TargetChoice;

/// Arguments of `crackbot calibrate views`.
#[derive(Debug, Args)]
pub struct ViewsArgs {
    /// The scene whose camera is calibrated (default: the built-in one).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub target: TargetChoice,
    /// Folder for views/, surface.png and target.toml.
    #[arg(long, default_value = "out/calibration-views")]
    pub out: PathBuf,
    /// Views of the calibration session.
    #[arg(long, default_value_t = 15)]
    pub count: usize,
    /// Seed of the poses and the sensor noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Where the target lies on the plate: centred.
pub fn centred_origin(spec: &TargetSpec, plate_mm: [f64; 2]) -> [f64; 2] {
    let [w, h] = spec.grid_mm();
    [(plate_mm[0] - w) / 2.0, (plate_mm[1] - h) / 2.0]
}

/// Renders and writes the views.
pub fn run(args: &ViewsArgs) -> Result<()> {
    let scene = Scene::load_or_default(args.scene.as_deref())?;
    let base = scene
        .camera
        .clone()
        .context("the scene has no camera ([camera] table) to calibrate")?;
    let spec = args.target.spec()?;
    let plate = scene.plate.size_mm;
    let origin = centred_origin(&spec, plate);
    let sheet = |p: [f64; 2]| spec.is_white([p[0] - origin[0], p[1] - origin[1]]);
    let views_dir = args.out.join("views");
    std::fs::create_dir_all(&views_dir)
        .with_context(|| format!("creating {}", views_dir.display()))?;
    let centre = [plate[0] / 2.0, plate[1] / 2.0];
    let poses = calibration_poses(&base, centre, plate[0].max(plate[1]), args.count, args.seed);
    let bar = ProgressBar::new(poses.len() as u64 + 1);
    for (i, pose) in poses.iter().enumerate() {
        let cam = Camera::from_spec(pose)?;
        let img = render_sheet(
            &cam,
            &sheet,
            &SheetOptions::default(),
            args.seed * 1000 + i as u64,
        );
        let p = views_dir.join(format!("view-{i:02}.png"));
        img.save(&p)
            .with_context(|| format!("writing {}", p.display()))?;
        bar.inc(1);
    }
    let cam = Camera::from_spec(&base)?;
    let img = render_sheet(
        &cam,
        &sheet,
        &SheetOptions::default(),
        args.seed * 1000 + 999,
    );
    let surface = args.out.join("surface.png");
    img.save(&surface)
        .with_context(|| format!("writing {}", surface.display()))?;
    bar.finish_and_clear();
    let target = args.out.join("target.toml");
    spec.save(&target)?;
    let o = args.out.display();
    println!(
        "{o}: {} views in views/, the target on the plate in surface.png, target.toml",
        poses.len()
    );
    println!("next:");
    println!("  crackbot calibrate camera {o}/views --target {o}/target.toml -o {o}/camera.toml");
    println!(
        "  crackbot calibrate surface {o}/surface.png --camera {o}/camera.toml --target {o}/target.toml --origin-mm {:.3},{:.3}",
        origin[0], origin[1]
    );
    Ok(())
}
