//! What the operator looks at: the frame with the corners found (green crosses) and lines drawn
//! through the fitted lens and pose (the target's tags in red, the plate's grid in blue), so a
//! bad calibration shows as lines off the printed edges.

use crackbot_calib::{Lens, Pose};
use crackbot_calib_target::{Found, TargetSpec};
use image::{GrayImage, Rgb, RgbImage};
use nalgebra::Vector3;

const GREEN: Rgb<u8> = Rgb([0, 220, 0]);
const RED: Rgb<u8> = Rgb([255, 40, 40]);
const BLUE: Rgb<u8> = Rgb([60, 140, 255]);

/// `image` with the corners of `found` and every tag of `spec` reprojected through `lens` at
/// `pose` (target → camera).
pub fn overlay(
    image: &GrayImage,
    found: &Found,
    lens: &Lens,
    pose: &Pose,
    spec: &TargetSpec,
) -> RgbImage {
    let mut out = to_rgb(image);
    for tag in spec.tags() {
        let s = spec.tag_mm;
        let [x, y] = tag.origin_mm;
        let square = [[x, y], [x + s, y], [x + s, y + s], [x, y + s], [x, y]];
        polyline(&mut out, lens, pose, &square, RED);
    }
    corners(&mut out, found);
    out
}

/// `image` with the corners of `found` and the plate's grid every `step_mm` over `extent`
/// (`[min, max]` corners, plate mm) drawn through `lens` at `plate` (plate → camera).
pub fn plate_grid(
    image: &GrayImage,
    found: &Found,
    lens: &Lens,
    plate: &Pose,
    extent: [[f64; 2]; 2],
    step_mm: f64,
) -> RgbImage {
    let mut out = to_rgb(image);
    let [lo, hi] = extent;
    let mut x = lo[0];
    while x <= hi[0] + 1e-9 {
        polyline(&mut out, lens, plate, &[[x, lo[1]], [x, hi[1]]], BLUE);
        x += step_mm;
    }
    let mut y = lo[1];
    while y <= hi[1] + 1e-9 {
        polyline(&mut out, lens, plate, &[[lo[0], y], [hi[0], y]], BLUE);
        y += step_mm;
    }
    corners(&mut out, found);
    out
}

fn to_rgb(image: &GrayImage) -> RgbImage {
    RgbImage::from_fn(image.width(), image.height(), |c, r| {
        let v = image.get_pixel(c, r)[0];
        Rgb([v, v, v])
    })
}

/// Green crosses on the corners found.
fn corners(out: &mut RgbImage, found: &Found) {
    for t in &found.tags {
        for c in t.corners_px {
            for d in -4..=4 {
                put(out, c[0] + f64::from(d), c[1], GREEN);
                put(out, c[0], c[1] + f64::from(d), GREEN);
            }
        }
    }
}

/// The plane polyline `pts` (mm, z = 0 of `pose`'s frame) through the lens, densely sampled so
/// its curvature shows.
fn polyline(out: &mut RgbImage, lens: &Lens, pose: &Pose, pts: &[[f64; 2]], colour: Rgb<u8>) {
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let n = (len * 4.0).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let p = Vector3::new(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), 0.0);
            if let Some(uv) = lens.project(pose.apply(p)) {
                put(out, uv[0], uv[1], colour);
            }
        }
    }
}

fn put(out: &mut RgbImage, u: f64, v: f64, colour: Rgb<u8>) {
    if u >= 0.0 && v >= 0.0 && u < f64::from(out.width()) && v < f64::from(out.height()) {
        out.put_pixel(u as u32, v as u32, colour);
    }
}
