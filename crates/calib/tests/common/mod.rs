//! What the calibration tests share: a webcam-like lens with known distortion, a flat target of
//! 9 × 6 points 25 mm apart, and views of it at random poses as a user takes them.
#![allow(dead_code, reason = "each test binary uses a part")]

use crackbot_calib::{Distortion, Intrinsics, Lens, Pose, View};
use nalgebra::{Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub const SIZE: [u32; 2] = [1280, 720];

pub fn target() -> Vec<[f64; 2]> {
    (0..6)
        .flat_map(|r| (0..9).map(move |c| [f64::from(c) * 25.0, f64::from(r) * 25.0]))
        .collect()
}

pub fn lens(k1: f64, k2: f64, p1: f64, p2: f64) -> Lens {
    Lens {
        intrinsics: Intrinsics {
            fx: 920.0,
            fy: 915.0,
            cx: 652.0,
            cy: 351.0,
        },
        distortion: Distortion {
            k1,
            k2,
            p1,
            p2,
            k3: 0.0,
        },
    }
}

/// A pose of the target as a user following the guide takes them: its centre 250–550 mm in
/// front, anywhere across the image (corners too, partly out of view), tilted 8° to
/// `max_tilt` about a random axis in its plane and turned about its normal at random.
pub fn random_pose(rng: &mut ChaCha8Rng, max_tilt: f64) -> Pose {
    let tilt = rng.random_range(8.0..max_tilt).to_radians();
    let axis_angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let spin: f64 = rng.random_range(-0.5..0.5);
    let r = Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(Vector3::new(axis_angle.cos(), axis_angle.sin(), 0.0)),
        tilt,
    ) * Rotation3::from_axis_angle(&Vector3::z_axis(), spin);
    let centre = r * Vector3::new(100.0, 62.5, 0.0);
    let distance = rng.random_range(250.0..550.0);
    // Where the target's centre is seen, as a fraction of the image (pinhole of the truth).
    let (fu, fv) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
    let ray = Vector3::new(
        (fu * f64::from(SIZE[0]) - 652.0) / 920.0,
        (fv * f64::from(SIZE[1]) - 351.0) / 915.0,
        1.0,
    );
    Pose::new(&r, ray * distance - centre)
}

/// The target's points seen through `lens` at `pose`, with Gaussian-ish noise of `sigma` px; the
/// points outside the image are left out.
pub fn view(lens: &Lens, pose: &Pose, sigma: f64, rng: &mut ChaCha8Rng) -> View {
    let mut v = View::default();
    for t in target() {
        let Some([u, w]) = lens.project(pose.apply(Vector3::new(t[0], t[1], 0.0))) else {
            continue;
        };
        if !(0.0..f64::from(SIZE[0])).contains(&u) || !(0.0..f64::from(SIZE[1])).contains(&w) {
            continue;
        }
        let noise = |rng: &mut ChaCha8Rng| {
            (0..4).map(|_| rng.random_range(-1.0..1.0)).sum::<f64>() * sigma / (4.0f64 / 3.0).sqrt()
        };
        v.target.push(t);
        v.image.push([u + noise(rng), w + noise(rng)]);
    }
    v
}

pub fn views(lens: &Lens, n: usize, sigma: f64, seed: u64) -> (Vec<View>, Vec<Pose>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut views = Vec::new();
    let mut poses = Vec::new();
    while views.len() < n {
        let pose = random_pose(&mut rng, 45.0);
        let v = view(lens, &pose, sigma, &mut rng);
        if v.target.len() >= 20 {
            views.push(v);
            poses.push(pose);
        }
    }
    (views, poses)
}
