//! A flat printed sheet (a calibration target) lying on the plate, seen by a scene's camera
//! through its lens: each pixel averages `samples × samples` points across it (the printed
//! edges come out anti-aliased, as a real sensor integrates them), then the frame's gain and
//! Gaussian sensor noise are applied. Also the random camera poses of a calibration session:
//! the camera carried by the arm over the sheet, as an operator would move it.

use image::GrayImage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::camera::{Camera, CameraSpec};
use crate::surface::Point;

/// How a sheet view is rendered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetOptions {
    /// Points averaged across each pixel, per axis.
    pub samples: u32,
    /// Grey level of the white paper.
    pub paper: f64,
    /// Grey level of the black ink.
    pub ink: f64,
    /// Grey level of what is around the sheet (the plate, the bench).
    pub background: f64,
    /// Standard deviation of the sensor noise, grey levels.
    pub noise_sigma: f64,
}

impl Default for SheetOptions {
    fn default() -> Self {
        SheetOptions {
            samples: 4,
            paper: 225.0,
            ink: 30.0,
            background: 120.0,
            noise_sigma: 2.0,
        }
    }
}

/// The view of `cam` of a sheet on the plate (z = 0): `is_white(p)` says what is printed at
/// the plate point `p` (`Some(true)` paper, `Some(false)` ink, `None` off the sheet). The
/// frame's gain is drawn from `seed` (±10 %), as is the noise.
pub fn render_sheet(
    cam: &Camera,
    is_white: &dyn Fn(Point) -> Option<bool>,
    options: &SheetOptions,
    seed: u64,
) -> GrayImage {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let gain = rng.random_range(0.9..1.1);
    let noise = Normal::new(0.0, options.noise_sigma.max(0.0)).ok();
    let n = options.samples.max(1);
    let step = 1.0 / f64::from(n);
    GrayImage::from_fn(cam.width(), cam.height(), |c, r| {
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let uv = [
                    f64::from(c) + (f64::from(i) + 0.5) * step,
                    f64::from(r) + (f64::from(j) + 0.5) * step,
                ];
                sum += match cam.plate_point(uv).and_then(is_white) {
                    Some(true) => options.paper,
                    Some(false) => options.ink,
                    None => options.background,
                };
            }
        }
        let mut v = gain * sum / f64::from(n * n);
        if let Some(noise) = &noise {
            v += noise.sample(&mut rng);
        }
        image::Luma([v.round().clamp(0.0, 255.0) as u8])
    })
}

/// `count` camera poses for calibrating `base`'s lens from a sheet centred at `centre` on the
/// plate: the camera 0.6–1.2 × `base`'s height above the plate, looking at points up to a third
/// of `reach_mm` from the centre (so the sheet falls in every part of the frame), tilted up to
/// about 35° and rolled up to ±30°. Same lens and image size as `base`.
pub fn calibration_poses(
    base: &CameraSpec,
    centre: Point,
    reach_mm: f64,
    count: usize,
    seed: u64,
) -> Vec<CameraSpec> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let height = base.position_mm[2].abs();
    (0..count)
        .map(|_| {
            let z = height * rng.random_range(0.6..1.2);
            let tilt = rng.random_range(0.0_f64..35.0).to_radians();
            let heading = rng.random_range(0.0..std::f64::consts::TAU);
            let off = z * tilt.tan();
            let look = [
                centre[0] + rng.random_range(-1.0..1.0) * reach_mm / 3.0,
                centre[1] + rng.random_range(-1.0..1.0) * reach_mm / 3.0,
            ];
            CameraSpec {
                position_mm: [
                    look[0] + off * heading.cos(),
                    look[1] + off * heading.sin(),
                    z,
                ],
                look_at_mm: look,
                roll_deg: rng.random_range(-30.0..30.0),
                ..base.clone()
            }
        })
        .collect()
}
