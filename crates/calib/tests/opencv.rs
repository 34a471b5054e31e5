//! The same matched points calibrated by OpenCV (`cv2.calibrateCamera`, its Python binding:
//! `scripts/opencv_check.sh`), an implementation independent of this crate: the two fits agree.

mod common;

use std::path::Path;
use std::process::Command;

use common::{lens, views, SIZE};
use crackbot_calib::{calibrate, Options};

fn opencv(views_json: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/opencv_check.sh");
    let out = Command::new("bash")
        .arg(script)
        .arg("calibrate")
        .arg(views_json)
        .args([SIZE[0].to_string(), SIZE[1].to_string()])
        .output()
        .expect("running scripts/opencv_check.sh");
    assert!(
        out.status.success(),
        "opencv_check failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("OpenCV's fit as JSON")
}

fn f(v: &serde_json::Value, key: &str) -> f64 {
    v[key].as_f64().unwrap_or_else(|| panic!("no {key} in {v}"))
}

#[test]
fn opencv_finds_the_same_lens_from_the_same_points() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (k1, seed) in [(-0.35, 21), (-0.15, 22), (0.1, 23)] {
        let truth = lens(k1, 0.3 * f64::abs(k1), 0.001, -0.0008);
        let (vs, _) = views(&truth, 20, 0.1, seed);
        let ours = calibrate(&vs, SIZE, &Options::default()).expect("our calibration");
        let path = dir.path().join(format!("views-{seed}.json"));
        std::fs::write(&path, serde_json::to_string(&vs).expect("JSON")).expect("writing views");
        let cv = opencv(&path);
        let (k, d) = (ours.lens.intrinsics, ours.lens.distortion.to_array());
        let cv_d: Vec<f64> = cv["dist"]
            .as_array()
            .expect("dist")
            .iter()
            .map(|x| x.as_f64().expect("a coefficient"))
            .collect();
        eprintln!(
            "k1 {k1:+.2}: ours fx {:.3} fy {:.3} cx {:.3} cy {:.3} d {d:.5?} RMS {:.4}; \
             OpenCV fx {:.3} fy {:.3} cx {:.3} cy {:.3} d {cv_d:.5?} RMS {:.4}",
            k.fx,
            k.fy,
            k.cx,
            k.cy,
            ours.rms_px,
            f(&cv, "fx"),
            f(&cv, "fy"),
            f(&cv, "cx"),
            f(&cv, "cy"),
            f(&cv, "rms_px")
        );
        // Both minimise the same error over the same model: the same minimum.
        assert!((k.fx - f(&cv, "fx")).abs() < 0.05, "fx");
        assert!((k.fy - f(&cv, "fy")).abs() < 0.05, "fy");
        assert!((k.cx - f(&cv, "cx")).abs() < 0.05, "cx");
        assert!((k.cy - f(&cv, "cy")).abs() < 0.05, "cy");
        for (ours, theirs) in d.iter().zip(&cv_d) {
            assert!((ours - theirs).abs() < 1e-4, "distortion {d:?} vs {cv_d:?}");
        }
        assert!((ours.rms_px - f(&cv, "rms_px")).abs() < 1e-3, "RMS");
    }
}
