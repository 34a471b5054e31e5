//! `crackbot-controller register`: the plate's frame in the arm's base frame, from points on the
//! plate, written to the site file's `[surface]` table.
//!
//! * `--points FILE`: points the operator jogged the finger's tip to (CSV `x_m,y_m,z_m`, the
//!   arm's base frame): the origin first, then a point along +x, then any more on the plate.
//! * `--touch-at X,Y,Z` (three or more, feature `ros2`): guarded touches by the ROS 2 arm, each
//!   starting above the plate at that point and moving along `--approach` until the arm meets
//!   the plate (see `crackbot_controller::ros2::guarded_touches`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use crackbot_controller::motion::register::frame_from_points;
use crackbot_controller::ros2::site::write_surface;

/// The registration's arguments.
#[derive(Debug, clap::Args)]
pub struct Register {
    /// The site file to write the [surface] table into (created if missing).
    #[arg(long)]
    site: PathBuf,
    /// Points the operator jogged to: CSV with a header, `x_m,y_m,z_m` in the arm's base frame.
    #[arg(long, conflicts_with = "touch_at")]
    points: Option<PathBuf>,
    /// A guarded touch starting here (m, base frame, above the plate); three or more.
    #[arg(long, value_parser = point3, num_args = 1)]
    touch_at: Vec<[f64; 3]>,
    /// The direction the finger approaches the plate in (base frame; default straight down).
    #[arg(long, value_parser = point3, default_value = "0,0,-1")]
    approach: [f64; 3],
    /// The ROS 2 configuration file (topics, frames) for `--touch-at`.
    #[arg(long)]
    ros2_config: Option<PathBuf>,
}

/// `x,y,z` as three finite numbers.
fn point3(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>().map_err(|e| format!("{t:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|a| a.is_finite()) => Ok([*x, *y, *z]),
        _ => Err(format!("{s:?} is not three finite numbers x,y,z")),
    }
}

/// Reads the jogged points' CSV.
fn read_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines.next().unwrap_or_default();
    if header.replace(' ', "") != "x_m,y_m,z_m" {
        bail!(
            "{}: the first line must be the header x_m,y_m,z_m, not {header:?}",
            path.display()
        );
    }
    lines
        .enumerate()
        .map(|(i, l)| {
            point3(l).map_err(|e| anyhow::anyhow!("{} line {}: {e}", path.display(), i + 2))
        })
        .collect()
}

/// Runs the registration.
pub fn run(r: &Register) -> Result<()> {
    let points = match &r.points {
        Some(p) => read_points(p)?,
        None => touch(r)?,
    };
    let frame = frame_from_points(&points, r.approach)?;
    write_surface(&r.site, &frame)?;
    let n = frame.normal();
    println!(
        "surface: origin ({:.4}, {:.4}, {:.4}) m, normal ({:.4}, {:.4}, {:.4}), from {} points: written to {}",
        frame.origin_m[0],
        frame.origin_m[1],
        frame.origin_m[2],
        n[0],
        n[1],
        n[2],
        points.len(),
        r.site.display()
    );
    Ok(())
}

#[cfg(feature = "ros2")]
fn touch(r: &Register) -> Result<Vec<[f64; 3]>> {
    use crackbot_controller::ros2::config::Ros2Config;
    if r.touch_at.len() < 3 {
        bail!("give --points FILE, or three or more --touch-at X,Y,Z");
    }
    let config = match &r.ros2_config {
        Some(p) => Ros2Config::load(p)?,
        None => Ros2Config::default(),
    };
    Ok(crackbot_controller::ros2::guarded_touches(
        &config,
        &r.touch_at,
        r.approach,
    )?)
}

#[cfg(not(feature = "ros2"))]
fn touch(_: &Register) -> Result<Vec<[f64; 3]>> {
    bail!("give --points FILE (guarded touches need the ROS 2 arm: build with `--features ros2`)")
}
