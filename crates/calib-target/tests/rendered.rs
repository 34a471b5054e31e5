//! Calibrations from rendered images with a known truth: the simulator's camera, given lens
//! distortion, renders the printed target at random poses of a calibration session; the tags
//! are found by the AprilTag library; the lens is fitted; then the target laid on the plate is
//! seen from the scene's camera and the plate's pose solved. Checked against the simulator's
//! own camera: intrinsics, distortion, and where each plate point is put.

use std::time::Instant;

use crackbot_calib::calibrate::{pixel_to_plane, solve_pose};
use crackbot_calib::{calibrate, Options, View};
use crackbot_calib_target::{TagFinder, TargetSpec};
use crackbot_sim::camera::{Camera, CameraSpec};
use crackbot_sim::render::{calibration_poses, render_sheet, SheetOptions};
use crackbot_sim::Scene;

/// The default scene's camera with `distortion`.
fn camera_spec(distortion: [f64; 5]) -> CameraSpec {
    let scene = Scene::builtin_default();
    CameraSpec {
        distortion,
        ..scene
            .camera
            .clone()
            .expect("the default scene has a camera")
    }
}

/// Where the target's origin lies on the 200 × 100 mm plate: centred.
fn placement(spec: &TargetSpec) -> [f64; 2] {
    let [w, h] = spec.grid_mm();
    [(200.0 - w) / 2.0, (100.0 - h) / 2.0]
}

fn render(cam: &CameraSpec, spec: &TargetSpec, origin: [f64; 2], seed: u64) -> image::GrayImage {
    let camera = Camera::from_spec(cam).expect("camera");
    let sheet = |p: [f64; 2]| spec.is_white([p[0] - origin[0], p[1] - origin[1]]);
    // 3 × 3 samples a pixel (the commands render 4 × 4): the same figures within their spread,
    // at 56 % of the rendering time in the test build.
    let options = SheetOptions {
        samples: 3,
        ..SheetOptions::default()
    };
    render_sheet(&camera, &sheet, &options, seed)
}

#[test]
fn a_distorted_camera_is_recovered_from_rendered_views_of_the_printed_target() {
    let spec = TargetSpec::default();
    let origin = placement(&spec);
    let mut finder = TagFinder::new().expect("detector");
    for (k1, seed) in [(-0.35, 1u64), (-0.15, 3), (0.1, 2)] {
        let d = [k1, 0.3 * f64::abs(k1), 0.001, -0.0008, 0.0];
        let base = camera_spec(d);
        let t0 = Instant::now();
        let mut views: Vec<View> = Vec::new();
        for (i, pose) in calibration_poses(&base, [100.0, 50.0], 200.0, 15, seed)
            .iter()
            .enumerate()
        {
            let img = render(pose, &spec, origin, seed * 100 + i as u64);
            let found = finder.find(&img, &spec).expect("detection");
            if found.tags.len() >= 4 {
                views.push(found.view());
            }
        }
        let rendered = t0.elapsed();
        let cal = calibrate(&views, base.resolution, &Options::default()).expect("calibration");
        let truth = Camera::from_spec(&base).expect("camera").lens();
        eprintln!(
            "k1 {k1:+.2}: {} views, RMS {:.3} px, {:?} vs truth {:?} ({rendered:.1?} to render and detect)",
            views.len(),
            cal.rms_px,
            cal.lens,
            truth
        );
        eprintln!("  per view {:.3?}", cal.view_rms_px);
        assert!(cal.rms_px <= 0.3, "RMS {} px", cal.rms_px);
        let (k, t) = (cal.lens.intrinsics, truth.intrinsics);
        assert!((k.fx - t.fx).abs() < 0.005 * t.fx && (k.fy - t.fy).abs() < 0.005 * t.fy);
        assert!(
            (k.cx - t.cx).abs() < 2.0 && (k.cy - t.cy).abs() < 2.0,
            "{k:?}"
        );
        let (dc, dt) = (cal.lens.distortion.to_array(), truth.distortion.to_array());
        assert!(
            (dc[0] - dt[0]).abs() < 0.01 && (dc[1] - dt[1]).abs() < 0.03,
            "{dc:?}"
        );
        assert!(
            (dc[2] - dt[2]).abs() < 5e-4 && (dc[3] - dt[3]).abs() < 5e-4,
            "{dc:?}"
        );

        // The plate: the target laid on it, seen by the scene's camera.
        let img = render(&base, &spec, origin, seed + 7);
        let view = finder.find(&img, &spec).expect("detection").view();
        let (pose, rms) = solve_pose(&cal.lens, &view, &Options::default()).expect("pose");
        let cam = Camera::from_spec(&base).expect("camera");
        let (mut worst, mut sum, mut n) = (0.0_f64, 0.0, 0.0);
        for iy in 0..=20 {
            for ix in 0..=40 {
                let p = [f64::from(ix) * 5.0, f64::from(iy) * 5.0];
                let Some(uv) = cam
                    .project([p[0], p[1], 0.0])
                    .filter(|&uv| cam.in_image(uv))
                else {
                    continue;
                };
                let q = pixel_to_plane(&cal.lens, &pose, uv).expect("on the plate");
                let e = (q[0] + origin[0] - p[0]).hypot(q[1] + origin[1] - p[1]);
                worst = worst.max(e);
                sum += e;
                n += 1.0;
            }
        }
        eprintln!(
            "  plate: pose RMS {rms:.3} px, error mean {:.3} mm, worst {worst:.3} mm",
            sum / n
        );
        assert!(sum / n <= 0.3 && worst <= 1.0);
    }
}
