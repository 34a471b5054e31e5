//! Calibrations of cameras whose truth is known: a lens with distortion drawn over a webcam's
//! range (k1 from −0.35 to +0.1), a flat target of 9 × 6 points 25 mm apart seen at random poses
//! within an arm's reach, pixel noise. The fit must find the lens, the poses and the plate.

use crackbot_calib::calibrate::{pixel_to_plane, solve_pose};
use crackbot_calib::{calibrate, CalibError, Lens, Options, Pose, View};
use nalgebra::{Rotation3, Vector3};
use proptest::prelude::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

mod common;

use common::{lens, view, views, SIZE};

/// Worst and mean distance (mm) between points of the plate and where the calibration puts the
/// pixels they are seen at, over a 250 × 150 mm plate around the target laid on it (10 mm grid;
/// points out of the image left out).
fn plate_errors(truth: &Lens, fitted: &Lens, pose_truth: &Pose, pose_fit: &Pose) -> (f64, f64) {
    let mut worst: f64 = 0.0;
    let mut sum = 0.0;
    let mut n = 0.0;
    for iy in 0..=15 {
        for ix in 0..=25 {
            let p = [f64::from(ix) * 10.0 - 25.0, f64::from(iy) * 10.0 - 12.5];
            let Some(uv) = truth.project(pose_truth.apply(Vector3::new(p[0], p[1], 0.0))) else {
                continue;
            };
            if !(0.0..f64::from(SIZE[0])).contains(&uv[0])
                || !(0.0..f64::from(SIZE[1])).contains(&uv[1])
            {
                continue;
            }
            let Some(b) = pixel_to_plane(fitted, pose_fit, uv) else {
                return (f64::INFINITY, f64::INFINITY);
            };
            let d = (p[0] - b[0]).hypot(p[1] - b[1]);
            worst = worst.max(d);
            sum += d;
            n += 1.0;
        }
    }
    (worst, sum / n)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, failure_persistence: None, ..ProptestConfig::default() })]

    /// (k2 goes with k1 as in real webcams, 0.2–0.5 × |k1|: a strong barrel with no k2 folds over
    /// before the image corners, where no lens maps a ray.)
    /// The goals of issue 80 on synthetic views: RMS ≤ 0.3 px, the plate within 0.3 mm mean and
    /// 1 mm worst (a plate seen from 400 mm, through the fitted lens and the
    /// plate's pose solved from one more view of the target laid on it; errors over the plate
    /// around it).
    #[test]
    fn a_distorted_webcam_is_recovered(
        k1 in -0.35f64..0.1,
        k2_share in 0.2f64..0.5,
        p1 in -0.002f64..0.002,
        p2 in -0.002f64..0.002,
        seed in 0u64..1000,
    ) {
        let truth = lens(k1, k2_share * k1.abs(), p1, p2);
        let (vs, _) = views(&truth, 25, 0.1, seed);
        let cal = calibrate(&vs, SIZE, &Options::default()).expect("a calibration");
        prop_assert!(cal.rms_px <= 0.3, "RMS {} px", cal.rms_px);
        let (k, t) = (cal.lens.intrinsics, truth.intrinsics);
        prop_assert!((k.fx - t.fx).abs() < 0.01 * t.fx, "fx {} vs {}", k.fx, t.fx);
        prop_assert!((k.cx - t.cx).abs() < 5.0 && (k.cy - t.cy).abs() < 5.0, "{k:?}");
        prop_assert!((cal.lens.distortion.k1 - k1).abs() < 0.02, "k1 {} vs {k1}", cal.lens.distortion.k1);

        // The plate: the target laid on it, seen once from above, 400 mm away.
        let plate = Pose::new(
            &Rotation3::from_euler_angles(std::f64::consts::PI + 0.15, 0.1, 0.3),
            Vector3::new(-90.0, -60.0, 400.0),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(seed + 1);
        let on_plate = view(&truth, &plate, 0.1, &mut rng);
        let (solved, rms) = solve_pose(&cal.lens, &on_plate, &Options::default()).expect("a pose");
        prop_assert!(rms <= 0.3, "pose RMS {rms}");
        let (worst, mean) = plate_errors(&truth, &cal.lens, &plate, &solved);
        prop_assert!(mean <= 0.3 && worst <= 1.0, "plate error mean {mean} mm, worst {worst} mm");
    }
}

#[test]
fn too_few_views_are_refused() {
    let (vs, _) = views(&lens(-0.2, 0.0, 0.0, 0.0), 2, 0.1, 1);
    assert_eq!(
        calibrate(&vs, SIZE, &Options::default()),
        Err(CalibError::TooFewViews { got: 2, need: 3 })
    );
}

#[test]
fn views_all_face_on_do_not_constrain_the_focal_length() {
    let truth = lens(-0.2, 0.0, 0.0, 0.0);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let vs: Vec<View> = (0..5)
        .map(|k| {
            let pose = Pose::new(
                &Rotation3::from_axis_angle(&Vector3::z_axis(), 0.1 * f64::from(k)),
                Vector3::new(-100.0, -60.0, 300.0 + 40.0 * f64::from(k)),
            );
            view(&truth, &pose, 0.1, &mut rng)
        })
        .collect();
    let err = calibrate(&vs, SIZE, &Options::default()).unwrap_err();
    assert!(matches!(err, CalibError::Unconstrained { .. }), "{err}");
}

#[test]
fn an_edge_on_view_is_refused_by_its_index() {
    let truth = lens(-0.1, 0.0, 0.0, 0.0);
    let (mut vs, _) = views(&truth, 4, 0.1, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let edge_on = Pose::new(
        &Rotation3::from_axis_angle(&Vector3::x_axis(), 80f64.to_radians()),
        Vector3::new(-100.0, -20.0, 300.0),
    );
    vs.insert(2, view(&truth, &edge_on, 0.1, &mut rng));
    match calibrate(&vs, SIZE, &Options::default()) {
        Err(CalibError::EdgeOn {
            view: 2, tilt_deg, ..
        }) => assert!(tilt_deg > 75.0),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_points_are_named() {
    let truth = lens(-0.1, 0.0, 0.0, 0.0);
    let (mut vs, _) = views(&truth, 4, 0.1, 7);
    vs[1].image[3][0] = f64::NAN;
    assert_eq!(
        calibrate(&vs, SIZE, &Options::default()),
        Err(CalibError::NotFinite { view: 1, point: 3 })
    );
    let (mut vs, _) = views(&truth, 4, 0.1, 7);
    vs[3].target.truncate(5);
    vs[3].image.truncate(5);
    assert!(matches!(
        calibrate(&vs, SIZE, &Options::default()),
        Err(CalibError::TooFewPoints {
            view: 3,
            got: 5,
            ..
        })
    ));
    let (mut vs, _) = views(&truth, 4, 0.1, 7);
    let line: Vec<[f64; 2]> = (0..10).map(|i| [f64::from(i) * 10.0, 0.0]).collect();
    vs[0].target.clone_from(&line);
    vs[0].image = line;
    assert!(matches!(
        calibrate(&vs, SIZE, &Options::default()),
        Err(CalibError::Degenerate { view: 0, .. })
    ));
}

/// The figures over issue 80's range of k1 (25 views, 0.1 px noise, seed 11), printed for the
/// record and held to its goals.
#[test]
fn the_fit_over_the_range_of_k1_meets_the_goals() {
    for k1 in [-0.35, -0.2, -0.05, 0.1] {
        let truth = lens(k1, 0.3 * k1.abs(), 0.001, -0.0008);
        let (vs, _) = views(&truth, 25, 0.1, 11);
        let start = std::time::Instant::now();
        let cal = calibrate(&vs, SIZE, &Options::default()).expect("a calibration");
        let took = start.elapsed();
        let plate = Pose::new(
            &Rotation3::from_euler_angles(std::f64::consts::PI + 0.15, 0.1, 0.3),
            Vector3::new(-90.0, -60.0, 400.0),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let (solved, _) = solve_pose(
            &cal.lens,
            &view(&truth, &plate, 0.1, &mut rng),
            &Options::default(),
        )
        .expect("the plate's pose");
        let (worst, mean) = plate_errors(&truth, &cal.lens, &plate, &solved);
        let (k, t) = (cal.lens.intrinsics, truth.intrinsics);
        eprintln!(
            "k1 {k1:+.2}: RMS {:.3} px, fx {:+.2} px, cx {:+.2} px, k1 {:+.4}, k2 {:+.4}; \
             plate mean {mean:.3} mm, worst {worst:.3} mm; {:.2} s",
            cal.rms_px,
            k.fx - t.fx,
            k.cx - t.cx,
            cal.lens.distortion.k1 - k1,
            cal.lens.distortion.k2 - truth.distortion.k2,
            took.as_secs_f64()
        );
        assert!(cal.rms_px <= 0.3 && mean <= 0.3 && worst <= 1.0);
    }
}
