//! `crackbot calibrate grab`: the calibration's views taken from the camera itself, in the
//! mode the missions will use, one every few seconds while the operator moves the target.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use crackbot_vision::camera::{grab, CameraSource, DEFAULT_TIMEOUT};
use indicatif::ProgressBar;

use crate::run::CaptureArgs;

/// Arguments of `crackbot calibrate grab`.
#[derive(Debug, Args)]
pub struct GrabArgs {
    /// The camera: a V4L2 device (/dev/video0), a video file or stream URL.
    #[arg(long)]
    pub camera: PathBuf,
    #[command(flatten)]
    pub capture: CaptureArgs,
    /// Frames to take.
    #[arg(long, default_value_t = 15)]
    pub count: u32,
    /// Seconds between frames (time to move the target).
    #[arg(long, default_value_t = 3.0)]
    pub interval_s: f64,
    /// Folder for view-NN.png.
    #[arg(long, default_value = "out/calibration-views/views")]
    pub out: PathBuf,
}

/// Takes the frames.
pub fn run(a: &GrabArgs) -> Result<()> {
    if !(a.interval_s.is_finite() && a.interval_s >= 0.0) {
        anyhow::bail!("--interval-s {}: expected seconds ≥ 0", a.interval_s);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let source = CameraSource::parse(&a.camera.to_string_lossy());
    let options = a.capture.options();
    let bar = ProgressBar::new(u64::from(a.count));
    let mut size = None;
    for i in 0..a.count {
        if i > 0 {
            std::thread::sleep(Duration::from_secs_f64(a.interval_s));
        }
        let frame = grab(&source, None, &options, DEFAULT_TIMEOUT)?;
        size = Some(frame.dimensions());
        let p = a.out.join(format!("view-{i:02}.png"));
        frame
            .save(&p)
            .with_context(|| format!("writing {}", p.display()))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let Some((w, h)) = size {
        println!(
            "{}: {} frames of {w}×{h} px; next: crackbot calibrate camera {} --target TARGET.toml",
            a.out.display(),
            a.count,
            a.out.display()
        );
    }
    Ok(())
}
