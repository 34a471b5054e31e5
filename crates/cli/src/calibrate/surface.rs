//! `crackbot calibrate surface`: the plate's pose from the target laid on it.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use crackbot_calib::calibrate::{pixel_to_plane, solve_pose};
use crackbot_calib::file::SurfaceTable;
use crackbot_calib::{CameraFile, Options, Pose};
use crackbot_calib_target::TagFinder;
use nalgebra::{Rotation3, Vector3};

use super::{images, show, TargetChoice};

/// Arguments of `crackbot calibrate surface`.
#[derive(Debug, Args)]
pub struct SurfaceArgs {
    /// The camera's image of the target lying flat on the plate, from where the camera stays
    /// for the missions.
    pub image: PathBuf,
    /// The lens's calibration file (`crackbot calibrate camera`).
    #[arg(long)]
    pub camera: PathBuf,
    #[command(flatten)]
    pub target: TargetChoice,
    /// Where the target's origin (the outer corner of its bottom-left tag's black square) lies
    /// on the plate, mm `X,Y`.
    #[arg(long, value_parser = pair, default_value = "0,0")]
    pub origin_mm: [f64; 2],
    /// The angle from the plate's x axis to the target's bottom row, degrees (anticlockwise
    /// seen from above).
    #[arg(long, default_value_t = 0.0)]
    pub rotation_deg: f64,
    /// The file to write (default: update --camera).
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// The plate's extent for --show's grid, mm `W,H` from its origin.
    #[arg(long, value_parser = pair, default_value = "200,100")]
    pub plate_mm: [f64; 2],
    /// Write the frame with the corners found and the plate's 10 mm grid through the fit.
    #[arg(long)]
    pub show: Option<PathBuf>,
}

/// Two finite numbers as `X,Y`.
fn pair(s: &str) -> Result<[f64; 2], String> {
    let v: Vec<&str> = s.split(',').collect();
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{t:?} is not a number"))
    };
    match v.as_slice() {
        [x, y] => Ok([num(x)?, num(y)?]),
        _ => Err(format!("{s:?}: expected two numbers, X,Y")),
    }
}

/// The plate → camera pose from the target → camera pose and where the target lies.
fn plate_pose(target: &Pose, origin: [f64; 2], rotation_deg: f64) -> Pose {
    // p_target = Rz(-θ) (p_plate - origin)
    let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), -rotation_deg.to_radians());
    let r = target.rotation() * rz;
    let t = target.translation() - r * Vector3::new(origin[0], origin[1], 0.0);
    Pose::new(&r, t)
}

/// Solves the plate's pose, reports it and writes the file.
pub fn run(args: &SurfaceArgs) -> Result<()> {
    let spec = args.target.spec()?;
    let mut file = CameraFile::load(&args.camera)?;
    let (path, image) = images::load(std::slice::from_ref(&args.image))?
        .pop()
        .context("one image")?;
    file.check_frame(&args.camera, image.width(), image.height())?;
    let found = TagFinder::new()?.find(&image, &spec)?;
    if found.tags.len() < 2 {
        bail!(
            "{}: {} of the target's tags found; the plate's pose needs at least 2 (is the whole \
             target in view, lit evenly, and is --target the printed one?)",
            path.display(),
            found.tags.len()
        );
    }
    let lens = file.lens();
    let (target_pose, rms) = solve_pose(&lens, &found.view(), &Options::default())
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let plate = plate_pose(&target_pose, args.origin_mm, args.rotation_deg);
    let centre = plate.camera_centre();
    let mid = [
        f64::from(image.width()) / 2.0,
        f64::from(image.height()) / 2.0,
    ];
    let scale = match (
        pixel_to_plane(&lens, &plate, mid),
        pixel_to_plane(&lens, &plate, [mid[0] + 1.0, mid[1]]),
    ) {
        (Some(a), Some(b)) => (a[0] - b[0]).hypot(a[1] - b[1]),
        _ => bail!(
            "{}: the image's centre does not see the plate",
            path.display()
        ),
    };
    println!(
        "plate: {} tags, RMS {rms:.3} px (≈ {:.3} mm on the plate); camera {:.1} mm above it at \
         ({:.1}, {:.1}) mm, tilted {:.1}°; {scale:.3} mm per pixel at the image's centre",
        found.tags.len(),
        rms * scale,
        centre.z,
        centre.x,
        centre.y,
        plate.tilt_deg()
    );
    file.surface = Some(SurfaceTable {
        rotation: plate.rotation,
        translation_mm: plate.translation,
        rms_px: rms,
    });
    let out = args.out.as_ref().unwrap_or(&args.camera);
    file.save(out)?;
    println!("{}: written with the plate's pose", out.display());
    if let Some(dir) = &args.show {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let extent = [[0.0, 0.0], [args.plate_mm[0], args.plate_mm[1]]];
        let img = show::plate_grid(&image, &found, &lens, &plate, extent, 10.0);
        let p = dir.join("surface-check.png");
        img.save(&p)
            .with_context(|| format!("writing {}", p.display()))?;
        println!(
            "{}: the plate's 10 mm grid through the calibration",
            p.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plate_pose_puts_the_target_where_it_lies() {
        let target = Pose::new(
            &Rotation3::from_euler_angles(3.0, 0.1, 0.4),
            Vector3::new(-40.0, 20.0, 250.0),
        );
        let (origin, deg) = ([30.0, 12.0], 20.0);
        let plate = plate_pose(&target, origin, deg);
        // The target's point (10, 5) lies on the plate at origin + Rz(θ)(10, 5).
        let (s, c) = deg.to_radians().sin_cos();
        let on_plate = Vector3::new(
            origin[0] + 10.0 * c - 5.0 * s,
            origin[1] + 10.0 * s + 5.0 * c,
            0.0,
        );
        let a = target.apply(Vector3::new(10.0, 5.0, 0.0));
        let b = plate.apply(on_plate);
        assert!((a - b).norm() < 1e-9, "{a} vs {b}");
    }
}
