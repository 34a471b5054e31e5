//! The Rust inference path (letterbox → ONNX Runtime → crack map → boxes by the dataset rule)
//! against the Python model's own outputs, saved next to the model at export time (`models/detector/reference/`, written by
//! `models/detector/make_reference.py` with onnxruntime in Python), for the shipped default
//! (`models/detector/`, CrackSeg), the pretrained-encoder alternative (`models/detector/effseg/`)
//! and CrackSeg fine-tuned with the crack tiles (`models/detector/crackseg-tiles/`), and bad
//! model files.
#![cfg(feature = "onnx")]

use std::path::{Path, PathBuf};

use crackbot_vision::onnx::{ModelOutput, OnnxDetector};
use crackbot_vision::preprocess::{letterbox, PostprocessParams};
use crackbot_vision::{DetectionSource, Detector, VisionError};
use serde_json::Value;

fn models() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/detector")
}

/// The folders of the shipped models, each with its `reference/`: the default (CrackSeg with a
/// box head), EffSeg (no box head) and CrackSeg fine-tuned with the crack tiles (a box head).
fn model_folders() -> [PathBuf; 3] {
    [
        models(),
        models().join("effseg"),
        models().join("crackseg-tiles"),
    ]
}

fn reference(folder: &Path) -> Value {
    let text =
        std::fs::read_to_string(folder.join("reference/reference.json")).expect("reference.json");
    serde_json::from_str(&text).expect("JSON")
}

fn f(v: &Value) -> f64 {
    v.as_f64().expect("number")
}

fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= abs + rel * b.abs()
}

#[test]
fn crack_maps_match_python_on_the_synthetic_input_at_every_size() {
    for folder in model_folders() {
        synthetic_input_matches(&folder);
    }
}

fn synthetic_input_matches(folder: &Path) {
    let r = reference(folder);
    for s in r["synthetic"].as_array().expect("synthetic") {
        let size = s["S"].as_u64().expect("S") as usize;
        let model = folder.join(s["model"].as_str().expect("model"));
        let mut d = OnnxDetector::load(&model, PostprocessParams::default(), 1).expect("load");
        assert_eq!(d.input_size(), size);
        assert_eq!(d.output(), ModelOutput::CrackMap);
        let mut x = vec![0f32; 3 * size * size];
        for c in 0..3 {
            for y in 0..size {
                for xx in 0..size {
                    x[(c * size + y) * size + xx] = ((c * 7 + y * 3 + xx * 5) % 17) as f32 / 16.0;
                }
            }
        }
        let map = d.run_tensor(&x).expect("run");
        let cells = s["cells"].as_u64().expect("cells") as usize;
        assert_eq!(map.len(), cells * cells, "{}", model.display());
        for (i, want) in s["first_values"]
            .as_array()
            .expect("values")
            .iter()
            .enumerate()
        {
            assert!(
                close(f64::from(map[i]), f(want), 1e-4, 1e-5),
                "S={size} cell {i}: {} vs {}",
                map[i],
                f(want)
            );
        }
        let sum: f64 = map.iter().map(|&v| f64::from(v)).sum();
        assert!(close(sum, f(&s["sum"]), 1e-4, 1e-3), "S={size}: sum {sum}");
        let best = s["max_index"].as_u64().expect("index") as usize;
        assert!(close(f64::from(map[best]), f(&s["max_value"]), 1e-4, 1e-5));
    }
}

#[test]
fn crack_maps_and_detections_match_python_on_real_photos() {
    for folder in model_folders() {
        real_photos_match(&folder);
    }
}

fn real_photos_match(folder: &Path) {
    let r = reference(folder);
    let mut d = OnnxDetector::load(
        &folder.join("crack-detector-320.onnx"),
        PostprocessParams {
            score_threshold: 0.0,
            box_head: true,
            ..PostprocessParams::default()
        },
        1,
    )
    .expect("load");
    let mut compared = 0;
    let mut head_boxes = 0;
    for im in r["images"].as_array().expect("images") {
        let file = folder
            .join("reference")
            .join(im["file"].as_str().expect("file"));
        let rgb = image::open(&file).expect("png").to_rgb8();
        assert_eq!(u64::from(rgb.width()), im["W"].as_u64().expect("W"));
        // The letterbox is the contract's, value for value.
        let (x, lb) = letterbox(&rgb, 320).expect("letterbox");
        assert!(close(f64::from(lb.scale), f(&im["scale"]), 1e-6, 0.0));
        let sum: f64 = x.iter().map(|&v| f64::from(v)).sum();
        let want = f(&im["input_checksum"]["sum"]);
        assert!(
            close(sum, want, 1e-6, 1e-3),
            "{}: input sum {sum} vs {want}",
            file.display()
        );
        for (k, w) in im["input_checksum"]["first8_row0_R"]
            .as_array()
            .expect("first8")
            .iter()
            .enumerate()
        {
            assert!(
                close(f64::from(x[k]), f(w), 0.0, 1e-6),
                "{}: input[{k}]",
                file.display()
            );
        }
        let map = d.crack_map(&rgb).expect("map");
        let map_sum: f64 = map.probabilities().iter().map(|&v| f64::from(v)).sum();
        assert!(
            close(map_sum, f(&im["map_sum"]), 1e-4, 1e-2),
            "{}: map sum {map_sum}",
            file.display()
        );
        let (found, with_map) = d.detect_with_map(&rgb).expect("detect");
        assert!(with_map.is_some());
        let want = im["detections"].as_array().expect("detections");
        assert_eq!(found.len(), want.len(), "{}: {found:?}", file.display());
        for (g, w) in found.iter().zip(want) {
            let b = w["bbox"].as_array().expect("bbox");
            for (got, w) in [g.bbox.x0, g.bbox.y0, g.bbox.x1, g.bbox.y1].iter().zip(b) {
                assert!(
                    close(f64::from(*got), f(w), 1e-4, 1e-3),
                    "{}: box {g:?} vs {b:?}",
                    file.display()
                );
            }
            assert!(close(f64::from(g.score), f(&w["score"]), 1e-3, 1e-5));
            // The box head's boxes (models that have one) come after the crack map's, box only.
            if w["source"] == "box_head" {
                assert_eq!(g.source, DetectionSource::BoxHead, "{}", file.display());
                assert!(g.shape.is_none() && g.score < 0.5);
                head_boxes += 1;
                continue;
            }
            assert_eq!(g.source, DetectionSource::Primary, "{}", file.display());
            let shape = g
                .shape
                .as_ref()
                .expect("a crack map detection has a course");
            assert!(shape.polyline.len() >= 2);
            for p in &shape.polyline {
                assert!(
                    p[0] >= g.bbox.x0 - 1e-3
                        && p[0] <= g.bbox.x1 + 1e-3
                        && p[1] >= g.bbox.y0 - 1e-3
                        && p[1] <= g.bbox.y1 + 1e-3,
                    "{}: the centre line leaves its box: {p:?} {g:?}",
                    file.display()
                );
            }
            compared += 1;
        }
    }
    assert!(
        compared > 0,
        "the reference images have no detection to compare"
    );
    // The CrackSeg models have a box head, and its boxes are compared too; EffSeg has none.
    assert_eq!(d.has_box_head(), head_boxes > 0, "{}", folder.display());
    assert_eq!(
        d.has_box_head(),
        !folder.ends_with("effseg"),
        "{}",
        folder.display()
    );
    let rgb = image::RgbImage::from_pixel(64, 48, image::Rgb([90, 90, 90]));
    match d.box_head_maps(&rgb) {
        Ok(head) => assert_eq!(head.cells(), 320 / 8),
        Err(e) => assert!(
            !d.has_box_head() && e.to_string().contains("no box head"),
            "{e}"
        ),
    }
}

#[test]
fn bad_model_files_are_named_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let garbage = dir.path().join("garbage.onnx");
    std::fs::write(&garbage, b"this is not an ONNX model").expect("write");
    let err = OnnxDetector::load(&garbage, PostprocessParams::default(), 1).unwrap_err();
    assert!(matches!(err, VisionError::Runtime(_)), "{err}");
    assert!(err.to_string().contains("garbage.onnx"), "{err}");
    let real = std::fs::read(models().join("crack-detector-320.onnx")).expect("model");
    let truncated = dir.path().join("truncated.onnx");
    std::fs::write(&truncated, &real[..real.len() / 2]).expect("write");
    let err = OnnxDetector::load(&truncated, PostprocessParams::default(), 1).unwrap_err();
    assert!(err.to_string().contains("truncated.onnx"), "{err}");
    let missing = dir.path().join("missing.onnx");
    let err = OnnxDetector::load(&missing, PostprocessParams::default(), 1).unwrap_err();
    assert!(
        matches!(err, VisionError::Io { .. }) && err.to_string().contains("missing.onnx"),
        "{err}"
    );
}

#[test]
fn odd_images_and_tensors_never_panic() {
    let mut d = OnnxDetector::load(
        &models().join("crack-detector-320.onnx"),
        PostprocessParams::default(),
        1,
    )
    .expect("load");
    for (w, h) in [(1, 1), (2000, 3), (3, 900), (320, 320)] {
        let img = image::RgbImage::from_pixel(w, h, image::Rgb([128, 128, 128]));
        let found = d.detect(&img).expect("detect");
        for det in found {
            assert!(det.bbox.x0 >= 0.0 && det.bbox.x1 <= w as f32 && det.bbox.y1 <= h as f32);
            assert!((0.0..=1.0).contains(&det.score));
        }
    }
    assert!(d.run_tensor(&[0.0; 10]).is_err());
}
