//! `crackbot calibrate camera`: the lens from views of the printed target.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use crackbot_calib::{calibrate, CalibError, CameraFile, Options, View};
use crackbot_calib_target::{Found, TagFinder, TargetSpec};

use super::{images, show, TargetChoice};

/// Arguments of `crackbot calibrate camera`.
#[derive(Debug, Args)]
pub struct CameraArgs {
    /// Images of the target (files, or folders of .png/.jpg), 10–20 views: near and far, tilted
    /// up to about 40° every way, the target reaching every corner of the frame.
    #[arg(required = true)]
    pub images: Vec<PathBuf>,
    #[command(flatten)]
    pub target: TargetChoice,
    /// The calibration file to write.
    #[arg(short, long, default_value = "out/camera.toml")]
    pub out: PathBuf,
    /// Fit k3 too (wide-angle lenses; a webcam is better without).
    #[arg(long)]
    pub k3: bool,
    /// Fewest tags for an image to count as a view.
    #[arg(long, default_value_t = 4)]
    pub min_tags: usize,
    /// Folder for each view with the corners found (green) and the fitted lens's reprojection
    /// of every tag (red): look at them before a mission.
    #[arg(long)]
    pub show: Option<PathBuf>,
}

/// One image's findings.
struct Seen {
    path: PathBuf,
    image: image::GrayImage,
    found: Found,
}

/// Finds the target in every image; keeps those with `min_tags` tags or more, saying which
/// were left out and why.
fn find_views(args: &CameraArgs, spec: &TargetSpec) -> Result<Vec<Seen>> {
    let imgs = images::load(&args.images)?;
    let total = imgs.len();
    let mut finder = TagFinder::new()?;
    let mut kept = Vec::new();
    for (path, image) in imgs {
        let found = finder.find(&image, spec)?;
        if found.tags.len() < args.min_tags {
            eprintln!(
                "{}: left out: {} of the target's tags found (need {}){}",
                path.display(),
                found.tags.len(),
                args.min_tags,
                strangers(&found)
            );
            continue;
        }
        kept.push(Seen { path, image, found });
    }
    if kept.is_empty() {
        bail!(
            "no target found in any of the {total} images (looked for tag36h11 ids {}–{}; is the \
             target well lit, in focus, and is --target the printed one?)",
            spec.first_id,
            spec.first_id + spec.cols * spec.rows - 1
        );
    }
    Ok(kept)
}

fn strangers(found: &Found) -> String {
    if found.strangers.is_empty() {
        String::new()
    } else {
        format!(
            "; saw tags {:?} that are not on this target (another --target?)",
            found.strangers
        )
    }
}

/// Names the image a calibration error is about.
fn explain(e: CalibError, seen: &[Seen]) -> anyhow::Error {
    let name = |k: usize| {
        seen.get(k)
            .map_or_else(String::new, |s| s.path.display().to_string())
    };
    match &e {
        CalibError::TooFewPoints { view, .. }
        | CalibError::NotFinite { view, .. }
        | CalibError::Degenerate { view, .. }
        | CalibError::EdgeOn { view, .. } => anyhow::anyhow!("{}: {e}", name(*view)),
        _ => anyhow::anyhow!("{e}"),
    }
}

/// Calibrates, reports and writes the file.
pub fn run(args: &CameraArgs) -> Result<()> {
    let spec = args.target.spec()?;
    let seen = find_views(args, &spec)?;
    let views: Vec<View> = seen.iter().map(|s| s.found.view()).collect();
    let size = [seen[0].image.width(), seen[0].image.height()];
    let options = Options {
        estimate_k3: args.k3,
        ..Options::default()
    };
    let cal = calibrate(&views, size, &options).map_err(|e| explain(e, &seen))?;
    report(&cal, &seen);
    let date = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
    let file = CameraFile::new(&cal.lens, size, views.len() as u32, cal.rms_px, date);
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    file.save(&args.out)?;
    println!(
        "{}: written (no plate pose yet: lay the target on the plate and run `crackbot calibrate \
         surface IMAGE --camera {}`)",
        args.out.display(),
        args.out.display()
    );
    if let Some(dir) = &args.show {
        write_show(dir, &seen, &cal, &spec)?;
    }
    Ok(())
}

fn report(cal: &crackbot_calib::Calibration, seen: &[Seen]) {
    let k = cal.lens.intrinsics;
    let d = cal.lens.distortion;
    println!(
        "lens: fx {:.2} fy {:.2} cx {:.2} cy {:.2} px; k1 {:+.5} k2 {:+.5} p1 {:+.6} p2 {:+.6} k3 {:+.5}",
        k.fx, k.fy, k.cx, k.cy, d.k1, d.k2, d.p1, d.p2, d.k3
    );
    println!(
        "RMS reprojection error {:.3} px over {} views:",
        cal.rms_px,
        seen.len()
    );
    let mut sorted = cal.view_rms_px.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    for (s, rms) in seen.iter().zip(&cal.view_rms_px) {
        let flag = if *rms > 3.0 * median.max(0.05) {
            "  <- much worse than the others: blurred, or the target not flat? retake it"
        } else {
            ""
        };
        println!(
            "  {:<40} {:>3} tags  {rms:.3} px{flag}",
            s.path.display(),
            s.found.tags.len()
        );
    }
}

fn write_show(
    dir: &Path,
    seen: &[Seen],
    cal: &crackbot_calib::Calibration,
    spec: &TargetSpec,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    for (s, pose) in seen.iter().zip(&cal.poses) {
        let img = show::overlay(&s.image, &s.found, &cal.lens, pose, spec);
        let name = s
            .path
            .file_stem()
            .map_or_else(|| "view".to_string(), |n| n.to_string_lossy().into_owned());
        let out = dir.join(format!("{name}-check.png"));
        img.save(&out)
            .with_context(|| format!("writing {}", out.display()))?;
    }
    println!(
        "{}: each view with the corners found and the lens's reprojection",
        dir.display()
    );
    Ok(())
}
