//! `crackbot calibrate`: the camera on a bench, from a printed target.
//!
//! * `target`: the printable target (PNG at true scale) and its description (`target.toml`).
//! * `grab`: the views taken from the camera in the missions' mode.
//! * `camera`: the lens (intrinsics and distortion) from several views of the target.
//! * `surface`: the plate's pose from one view of the target laid on it.
//! * `views` (simulator): rendered views of the target through a scene's camera, to try the
//!   two above without a camera.
//! * `check`: a calibration file read and checked, optionally against a frame's size.
//!
//! One file per step; `show.rs` draws what was found and what the fit predicts.

mod camera;
mod grab;
mod images;
mod show;
mod surface;
mod target;
#[cfg(feature = "sim")]
mod views;

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};
use crackbot_calib_target::TargetSpec;

/// `crackbot calibrate …`.
#[derive(Debug, Subcommand)]
pub enum CalibrateCommand {
    /// Write the printable target: a PNG at true scale (its pixel size in the file) and the
    /// target.toml that describes it. Print it at 100 % ("actual size") and measure one tag.
    Target(target::TargetArgs),
    /// Take the views from the camera, in the mode the missions use (--camera-size, …), one
    /// every --interval-s while you move the target.
    Grab(grab::GrabArgs),
    /// The lens from views of the printed target: intrinsics and distortion (OpenCV's model),
    /// with the RMS reprojection error; writes the calibration file.
    Camera(camera::CameraArgs),
    /// The plate's pose from one view of the target laid on it: adds [surface] to the
    /// calibration file, giving pixel → plate millimetres through the lens.
    Surface(surface::SurfaceArgs),
    /// [simulator] Rendered views of the target through a scene's camera (its lens included),
    /// and the target laid on the plate: try `camera` and `surface` without hardware.
    #[cfg(feature = "sim")]
    Views(views::ViewsArgs),
    /// Read and check a calibration file (and, with --image, that it fits the frame's size).
    Check {
        /// The calibration file.
        file: PathBuf,
        /// A frame from the camera, to check its size.
        #[arg(long)]
        image: Option<PathBuf>,
    },
}

/// The target's description, shared by the commands.
#[derive(Debug, Args)]
pub struct TargetChoice {
    /// The target's description (`crackbot calibrate target` writes it); default: the built-in
    /// 8 × 4 grid of 18 mm tags.
    #[arg(long)]
    pub target: Option<PathBuf>,
}

impl TargetChoice {
    fn spec(&self) -> Result<TargetSpec> {
        Ok(match &self.target {
            Some(p) => TargetSpec::load(p)?,
            None => TargetSpec::default(),
        })
    }
}

/// Runs one `crackbot calibrate` command.
pub fn calibrate(cmd: CalibrateCommand) -> Result<()> {
    match cmd {
        CalibrateCommand::Target(a) => target::run(&a),
        CalibrateCommand::Grab(a) => grab::run(&a),
        CalibrateCommand::Camera(a) => camera::run(&a),
        CalibrateCommand::Surface(a) => surface::run(&a),
        #[cfg(feature = "sim")]
        CalibrateCommand::Views(a) => views::run(&a),
        CalibrateCommand::Check { file, image } => check(&file, image.as_deref()),
    }
}

/// `crackbot calibrate check`.
fn check(file: &std::path::Path, image: Option<&std::path::Path>) -> Result<()> {
    let cal = crackbot_calib::CameraFile::load(file)?;
    if let Some(img) = image {
        let (w, h) =
            image::image_dimensions(img).map_err(|e| anyhow::anyhow!("{}: {e}", img.display()))?;
        cal.check_frame(file, w, h)?;
    }
    let k = cal.lens();
    println!(
        "{}: {}×{} px, fx {:.2} fy {:.2} cx {:.2} cy {:.2}, distortion {:?}, RMS {:.3} px over {} views, {}",
        file.display(),
        cal.image.width,
        cal.image.height,
        k.intrinsics.fx,
        k.intrinsics.fy,
        k.intrinsics.cx,
        k.intrinsics.cy,
        cal.lens.distortion,
        cal.lens.rms_px,
        cal.lens.views,
        match &cal.surface {
            Some(s) => format!("plate pose known (RMS {:.3} px)", s.rms_px),
            None => "no plate pose yet (crackbot calibrate surface)".to_string(),
        }
    );
    Ok(())
}
