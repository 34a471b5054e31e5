//! Homography fitting against a synthetic pinhole camera looking at the plane z = 0 (mm), degenerate
//! input, RANSAC with outliers, the calibration file, and a round-trip property.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use crackbot_vision::homography::{
    fit_dlt, fit_ransac, Homography, HomographyCalibration, PointPair,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A pinhole camera: intrinsics and a world → camera pose.
struct Camera {
    k: Matrix3<f64>,
    r: Rotation3<f64>,
    t: Vector3<f64>,
}

impl Camera {
    /// Camera at `centre` (mm), rotated by roll/pitch/yaw from looking straight along +z.
    fn new(f: (f64, f64), c: (f64, f64), angles: (f64, f64, f64), centre: Vector3<f64>) -> Self {
        let k = Matrix3::new(f.0, 0.0, c.0, 0.0, f.1, c.1, 0.0, 0.0, 1.0);
        let r = Rotation3::from_euler_angles(angles.0, angles.1, angles.2);
        let t = -(r * centre);
        Self { k, r, t }
    }

    fn default_camera() -> Self {
        Self::new(
            (800.0, 780.0),
            (320.0, 240.0),
            (0.15, -0.1, 0.05),
            Vector3::new(100.0, 50.0, -450.0),
        )
    }

    /// Pixel of surface point (x, y, 0), `None` if behind the camera.
    fn project(&self, x: f64, y: f64) -> Option<[f64; 2]> {
        let pc = self.r * Vector3::new(x, y, 0.0) + self.t;
        if pc.z <= 1.0 {
            return None;
        }
        let p = self.k * pc;
        Some([p.x / p.z, p.y / p.z])
    }

    /// Surface point of a pixel (ray-plane intersection).
    fn back_project(&self, u: f64, v: f64) -> [f64; 2] {
        let ray_c = self.k.try_inverse().unwrap() * Vector3::new(u, v, 1.0);
        let ray_w = self.r.inverse() * ray_c;
        let centre = -(self.r.inverse() * self.t);
        let s = -centre.z / ray_w.z;
        let p = centre + ray_w * s;
        [p.x, p.y]
    }

    fn grid_pairs(&self, nx: usize, ny: usize) -> Vec<PointPair> {
        let mut pairs = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                let x = 200.0 * i as f64 / (nx - 1) as f64;
                let y = 100.0 * j as f64 / (ny - 1) as f64;
                pairs.push(PointPair::new(self.project(x, y).unwrap(), [x, y]));
            }
        }
        pairs
    }
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.random::<f64>().max(1e-300);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[test]
fn exact_pairs_give_an_exact_homography() {
    let cam = Camera::default_camera();
    let pairs = cam.grid_pairs(4, 3);
    let h = fit_dlt(&pairs).unwrap();
    let stats = h.reprojection_errors(&pairs);
    assert!(stats.max_mm < 1e-9 && stats.max_px < 1e-9, "{stats:?}");
    // Held-out points over the 200 × 100 mm plane.
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..200 {
        let (x, y) = (rng.random_range(0.0..200.0), rng.random_range(0.0..100.0));
        let px = cam.project(x, y).unwrap();
        let s = h.pixel_to_surface(px).unwrap();
        assert!((s[0] - x).hypot(s[1] - y) < 1e-6, "{s:?} vs {x} {y}");
        let back = h.surface_to_pixel([x, y]).unwrap();
        assert!((back[0] - px[0]).hypot(back[1] - px[1]) < 1e-6);
        let s2 = cam.back_project(px[0], px[1]);
        assert!((s2[0] - x).hypot(s2[1] - y) < 1e-6);
    }
    // Minimal case: exactly 4 pairs.
    let four = [pairs[0], pairs[2], pairs[9], pairs[11]];
    let h4 = fit_dlt(&four).unwrap();
    let s = h4
        .pixel_to_surface(cam.project(123.0, 45.0).unwrap())
        .unwrap();
    assert!((s[0] - 123.0).hypot(s[1] - 45.0) < 1e-6);
    assert_eq!(h.matrix()[2][2], 1.0);
}

#[test]
fn noisy_pairs_give_sub_millimetre_error() {
    let cam = Camera::default_camera();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let pairs: Vec<PointPair> = cam
        .grid_pairs(5, 4)
        .into_iter()
        .map(|p| {
            PointPair::new(
                [
                    p.pixel[0] + 0.5 * gauss(&mut rng),
                    p.pixel[1] + 0.5 * gauss(&mut rng),
                ],
                p.surface,
            )
        })
        .collect();
    assert_eq!(pairs.len(), 20);
    let h = fit_dlt(&pairs).unwrap();
    let stats = h.reprojection_errors(&pairs);
    assert!(stats.rms_px < 1.0, "{stats:?}");
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        let (x, y) = (rng.random_range(0.0..200.0), rng.random_range(0.0..100.0));
        let s = h.pixel_to_surface(cam.project(x, y).unwrap()).unwrap();
        worst = worst.max((s[0] - x).hypot(s[1] - y));
    }
    assert!(worst < 1.0, "worst held-out error {worst} mm");
}

#[test]
fn ransac_finds_the_inliers_among_30_percent_outliers() {
    let cam = Camera::default_camera();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut pairs = cam.grid_pairs(8, 5);
    let mut truth = vec![true; pairs.len()];
    for (i, p) in pairs.iter_mut().enumerate() {
        p.pixel[0] += 0.3 * gauss(&mut rng);
        p.pixel[1] += 0.3 * gauss(&mut rng);
        if i % 10 < 3 {
            // Gross outlier: a wrong surface point, 20-80 mm away.
            let a = rng.random_range(0.0..std::f64::consts::TAU);
            let d = rng.random_range(20.0..80.0);
            p.surface = [p.surface[0] + d * a.cos(), p.surface[1] + d * a.sin()];
            truth[i] = false;
        }
    }
    // Plain DLT is pulled off by the outliers.
    let plain = fit_dlt(&pairs).unwrap();
    let fit = fit_ransac(&pairs, 2.0, 500, 42).unwrap();
    assert_eq!(fit.inliers, truth);
    assert_eq!(fit.inlier_count(), 28);
    let mut worst: f64 = 0.0;
    let mut worst_plain: f64 = 0.0;
    for _ in 0..200 {
        let (x, y) = (rng.random_range(0.0..200.0), rng.random_range(0.0..100.0));
        let px = cam.project(x, y).unwrap();
        let s = fit.homography.pixel_to_surface(px).unwrap();
        worst = worst.max((s[0] - x).hypot(s[1] - y));
        let s = plain.pixel_to_surface(px).unwrap();
        worst_plain = worst_plain.max((s[0] - x).hypot(s[1] - y));
    }
    assert!(worst < 1.0, "RANSAC worst {worst} mm");
    assert!(worst_plain > 2.0, "plain DLT worst {worst_plain} mm");
    // Deterministic for a seed.
    assert_eq!(fit_ransac(&pairs, 2.0, 500, 42).unwrap(), fit);
    // Bad parameters.
    assert!(fit_ransac(&pairs, 0.0, 500, 42).is_err());
    assert!(fit_ransac(&pairs, f64::NAN, 500, 42).is_err());
    assert!(fit_ransac(&pairs, 2.0, 0, 42).is_err());
    assert!(fit_ransac(&pairs[..3], 2.0, 10, 42).is_err());
    // A threshold so small that no fifth pair agrees with any sample.
    let e = fit_ransac(&pairs, 1e-9, 50, 42).unwrap_err().to_string();
    assert!(e.contains("5 or more inliers"), "{e}");
    // Exactly 4 pairs: the exact fit is the consensus.
    let four = Camera::default_camera().grid_pairs(2, 2);
    assert_eq!(fit_ransac(&four, 0.1, 10, 1).unwrap().inlier_count(), 4);
}

fn square() -> Vec<PointPair> {
    vec![
        PointPair::new([0.0, 0.0], [0.0, 0.0]),
        PointPair::new([100.0, 0.0], [50.0, 0.0]),
        PointPair::new([100.0, 100.0], [50.0, 50.0]),
        PointPair::new([0.0, 100.0], [0.0, 50.0]),
        PointPair::new([50.0, 30.0], [25.0, 15.0]),
    ]
}

#[test]
fn degenerate_input_is_rejected() {
    let ok = square();
    assert!(fit_dlt(&ok).is_ok());
    let msg = |pairs: &[PointPair]| fit_dlt(pairs).unwrap_err().to_string();
    // Too few.
    assert!(msg(&ok[..3]).contains("at least 4"));
    assert!(msg(&[]).contains("at least 4"));
    // Non-finite on either side.
    for bad in [f64::NAN, f64::INFINITY] {
        let mut p = ok.clone();
        p[2].pixel[1] = bad;
        assert!(msg(&p).contains("not finite"));
        let mut p = ok.clone();
        p[1].surface[0] = bad;
        assert!(msg(&p).contains("not finite"));
    }
    // Duplicate points.
    let mut p = ok.clone();
    p[4].pixel = p[0].pixel;
    assert!(msg(&p).contains("same point"), "{}", msg(&p));
    let mut p = ok.clone();
    p[4].surface = p[2].surface;
    assert!(msg(&p).contains("same point"));
    // All collinear (pixel side, surface side).
    let line: Vec<PointPair> = (0..6)
        .map(|i| {
            PointPair::new(
                [i as f64 * 10.0, i as f64 * 5.0],
                [(i * i) as f64, i as f64 * 3.0 + 1.0],
            )
        })
        .collect();
    assert!(msg(&line).contains("one line"));
    let line2: Vec<PointPair> = (0..6)
        .map(|i| {
            PointPair::new(
                [(i * i) as f64, i as f64 * 3.0 + 1.0],
                [i as f64 * 10.0, 7.0],
            )
        })
        .collect();
    assert!(
        msg(&line2).contains("surface points lie on one line"),
        "{}",
        msg(&line2)
    );
    // All but one collinear.
    let mut almost: Vec<PointPair> = (0..5)
        .map(|i| {
            PointPair::new(
                [i as f64 * 10.0, 0.0],
                [i as f64, i as f64 * 0.5 + (i % 2) as f64],
            )
        })
        .collect();
    almost.push(PointPair::new([20.0, 30.0], [7.0, 9.0]));
    assert!(msg(&almost).contains("but point 5"), "{}", msg(&almost));
    // Ill-conditioned: consistent with no unique homography. Four points of which the pixel side
    // is a proper quadrilateral but the surface side is a quadrilateral folded through itself
    // (a "bow tie"): the fit needs to send a point through infinity.
    let bowtie = vec![
        PointPair::new([0.0, 0.0], [0.0, 0.0]),
        PointPair::new([100.0, 0.0], [100.0, 100.0]),
        PointPair::new([100.0, 100.0], [100.0, 0.0]),
        PointPair::new([0.0, 100.0], [0.0, 100.0]),
    ];
    let e = msg(&bowtie);
    println!("bow tie: {e}");
    assert!(
        e.contains("infinity") || e.contains("vanishing line") || e.contains("ill-conditioned"),
        "{e}"
    );
    // Points that differ by less than the tolerance relative to their spread: degenerate.
    let tiny: Vec<PointPair> = square()
        .into_iter()
        .map(|p| {
            PointPair::new(
                [1e6 + p.pixel[0] * 1e-12, 1e6 + p.pixel[1] * 1e-12],
                p.surface,
            )
        })
        .collect();
    assert!(fit_dlt(&tiny).is_err());
    // Huge but finite values do not panic.
    let huge: Vec<PointPair> = square()
        .into_iter()
        .map(|p| PointPair::new([p.pixel[0] * 1e300, p.pixel[1] * 1e300], p.surface))
        .collect();
    let _ = fit_dlt(&huge);
    // The same checks guard RANSAC.
    assert!(fit_ransac(&line, 1.0, 10, 0).is_err());
    assert!(fit_ransac(&almost, 1.0, 10, 0).is_err());
}

#[test]
fn ill_conditioned_system_is_rejected() {
    // Three of the four surface points collinear: caught by the geometry check.
    let pairs = vec![
        PointPair::new([0.0, 0.0], [0.0, 0.0]),
        PointPair::new([1.0, 0.0], [1.0, 1.0]),
        PointPair::new([0.0, 1.0], [2.0, 2.0]),
        PointPair::new([1.0, 1.0], [5.0, 3.0]),
    ];
    assert!(fit_dlt(&pairs).is_err());
    // Four pairs clustered within 1e-5 of a unit next to one far pair: distinct, not collinear, but
    // the normalised system has no well-determined solution.
    let cluster = |d: f64| {
        let q = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut pairs: Vec<PointPair> = q
            .iter()
            .map(|p| {
                PointPair::new(
                    [100.0 + p[0] * d, 100.0 + p[1] * d],
                    [50.0 + 2.0 * p[0] * d, 20.0 + 3.0 * p[1] * d],
                )
            })
            .collect();
        pairs.push(PointPair::new([500.0, 700.0], [300.0, 80.0]));
        pairs
    };
    let e = fit_dlt(&cluster(1e-5)).unwrap_err().to_string();
    assert!(e.contains("ill-conditioned"), "{e}");
    // Whatever the scale of the cluster, an error and never a panic.
    for d in [1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-7, 1e-12] {
        assert!(fit_dlt(&cluster(d)).is_err());
    }
}

#[test]
fn from_matrix_checks_the_matrix() {
    assert!(Homography::from_matrix([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_ok());
    assert!(Homography::from_matrix([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).is_err());
    assert!(
        Homography::from_matrix([[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_err()
    );
    assert!(Homography::from_matrix([[0.0; 3]; 3]).is_err());
    // A point on the vanishing line maps to infinity: an error, not inf/NaN.
    let h = Homography::from_matrix([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 1.0]]).unwrap();
    assert!(h.pixel_to_surface([-1.0, 5.0]).is_err());
    assert!(h.pixel_to_surface([f64::NAN, 5.0]).is_err());
    assert!(h.pixel_to_surface([1.0, 5.0]).is_ok());
}

#[test]
fn calibration_file_round_trips_and_is_validated() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("homography.toml");
    let cam = Camera::default_camera();
    let cal = HomographyCalibration::fit(cam.grid_pairs(4, 3)).unwrap();
    cal.save(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("surface_units = \"mm\""), "{text}");
    let loaded = HomographyCalibration::load(&path).unwrap();
    assert_eq!(loaded, cal);
    let h = loaded.homography().unwrap();
    let s = h
        .pixel_to_surface(cam.project(50.0, 60.0).unwrap())
        .unwrap();
    assert!((s[0] - 50.0).hypot(s[1] - 60.0) < 1e-6);

    let write_and_load = |c: &HomographyCalibration| {
        let p = dir.path().join("bad.toml");
        std::fs::write(&p, toml::to_string(c).unwrap()).unwrap();
        let e = HomographyCalibration::load(&p).unwrap_err().to_string();
        assert!(e.contains("bad.toml"), "{e}");
        e
    };
    // Matrix edited without refitting.
    let mut bad = cal.clone();
    bad.matrix[0][2] += 1.0;
    assert!(write_and_load(&bad).contains("does not match"));
    // Singular matrix.
    let mut bad = cal.clone();
    bad.matrix = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]];
    assert!(write_and_load(&bad).contains("singular"));
    // Wrong units.
    let mut bad = cal.clone();
    bad.surface_units = "inch".into();
    assert!(write_and_load(&bad).contains("units"));
    // Too few pairs.
    let mut bad = cal.clone();
    bad.pairs.truncate(3);
    assert!(write_and_load(&bad).contains("at least 4"));
    // Negative error.
    let mut bad = cal.clone();
    bad.rms_mm = -1.0;
    assert!(write_and_load(&bad).contains("rms_mm"));
    // Not TOML / missing field / missing file.
    let p = dir.path().join("garbage.toml");
    std::fs::write(&p, "matrix = 3").unwrap();
    assert!(HomographyCalibration::load(&p)
        .unwrap_err()
        .to_string()
        .contains("garbage.toml"));
    assert!(HomographyCalibration::load(dir.path().join("none.toml")).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn pixel_surface_pixel_round_trips(
        f in 400.0f64..1500.0,
        aspect in 0.9f64..1.1,
        cx in 200.0f64..400.0,
        cy in 150.0f64..300.0,
        roll in -0.3f64..0.3,
        pitch in -0.3f64..0.3,
        yaw in -3.1f64..3.1,
        dist in 300.0f64..900.0,
        ox in 50.0f64..150.0,
        oy in 25.0f64..75.0,
        probes in proptest::collection::vec((0.0f64..200.0, 0.0f64..100.0), 10),
    ) {
        let cam = Camera::new((f, f * aspect), (cx, cy), (roll, pitch, yaw), Vector3::new(ox, oy, -dist));
        let pairs = cam.grid_pairs(3, 3);
        let h = fit_dlt(&pairs).unwrap();
        for (x, y) in probes {
            let px = cam.project(x, y).unwrap();
            let s = h.pixel_to_surface(px).unwrap();
            prop_assert!((s[0] - x).hypot(s[1] - y) < 1e-6, "{:?} vs {} {}", s, x, y);
            let back = h.surface_to_pixel(s).unwrap();
            prop_assert!((back[0] - px[0]).hypot(back[1] - px[1]) < 1e-6);
        }
    }
}
