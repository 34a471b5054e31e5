//! `crackbot detect`, `eval-detector` and `homography` end to end: the real binary, the real model
//! through ONNX Runtime, real photos (`../shared/data/cracks`), and bad input.

use std::path::{Path, PathBuf};

use crackbot_tests::{crackbot, text};
use serde_json::Value;

/// The real crack photos (`../shared/data/cracks`, or `$CRACKBOT_DATA_DIR/cracks`).
fn cracks() -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::CRACKS)
}
/// The default model's reference outputs.
const REFERENCE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/models/detector/crackseg-tiles/reference"
);

fn ok_json(args: &[&str]) -> Value {
    let out = crackbot(args);
    assert!(
        out.status.success(),
        "crackbot {args:?}: {}",
        text(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn fails_naming(args: &[&str], what: &str) {
    let out = crackbot(args);
    assert!(!out.status.success(), "crackbot {args:?} should fail");
    let err = text(&out.stderr);
    assert!(
        err.contains(what),
        "crackbot {args:?}: error does not name {what:?}: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

/// A top-down camera 600 px wide looking at a 200 × 100 mm plate with a slight tilt: exact
/// pixel ↔ mm pairs as CSV.
fn write_pairs(path: &Path, collinear: bool) {
    let project = |x: f64, y: f64| {
        let (xc, yc, zc) = (x - 100.0 + 0.05 * y, y - 50.0, 400.0 + 0.1 * x);
        (800.0 * xc / zc + 320.0, 800.0 * yc / zc + 240.0)
    };
    let mut csv = String::from("u,v,x_mm,y_mm\n");
    let plate = [
        (0.0, 0.0),
        (200.0, 0.0),
        (200.0, 100.0),
        (0.0, 100.0),
        (100.0, 50.0),
        (40.0, 70.0),
    ];
    for (i, (x, y)) in plate.into_iter().enumerate() {
        // Collinear: distinct points along the plate's bottom edge.
        let (x, y) = if collinear {
            (30.0 * i as f64, 0.0)
        } else {
            (x, y)
        };
        let (u, v) = project(x, y);
        csv += &format!("{u},{v},{x},{y}\n");
    }
    std::fs::write(path, csv).expect("pairs");
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn detect_with_calibration_annotation_and_fusion() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pairs = dir.path().join("pairs.csv");
    let cal = dir.path().join("camera.toml");
    write_pairs(&pairs, false);
    let out = crackbot(&["homography", "fit", s(&pairs), "--out", s(&cal)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // The plate's centre (100, 50) mm projects to pixel (320 + 800·5/410, 240).
    let centre_u = 320.0 + 800.0 * 2.5 / 410.0;
    let check = crackbot(&[
        "homography",
        "check",
        s(&cal),
        "--pixel",
        &format!("{centre_u},240"),
    ]);
    assert!(check.status.success(), "{}", text(&check.stderr));
    assert!(
        text(&check.stdout).contains("(100.000, 50.000) mm"),
        "{}",
        text(&check.stdout)
    );

    let image = format!("{REFERENCE}/ref_uav75.png");
    let annotated = dir.path().join("annotated");
    let r = ok_json(&[
        "detect",
        &image,
        &image,
        &image,
        "--threshold",
        "0.05",
        "--calibration",
        s(&cal),
        "--fuse",
        "--annotate",
        s(&annotated),
        "--json",
    ]);
    assert!(r["detector"]
        .as_str()
        .expect("detector")
        .starts_with("onnx:"));
    let images = r["images"].as_array().expect("images");
    assert_eq!(images.len(), 3);
    let dets = images[0]["detections"].as_array().expect("detections");
    assert!(
        !dets.is_empty(),
        "the reference photo has detections at 0.05"
    );
    for d in dets {
        assert!(d["score"].as_f64().expect("score") >= 0.05);
        assert_eq!(d["centre_mm"].as_array().expect("centre_mm").len(), 2);
        // The crack's course, for laying slides across it: in pixels and on the surface.
        let px = d["polyline_px"].as_array().expect("polyline_px");
        let mm = d["polyline_mm"].as_array().expect("polyline_mm");
        assert!(px.len() >= 2 && px.len() == mm.len(), "{d}");
        assert_eq!(d["axis_px"].as_array().expect("axis_px").len(), 2);
        assert!(d["length_mm"].as_f64().expect("length_mm") > 0.0);
    }
    // Three copies of one frame fuse into the same detections, each seen 3 times.
    let fused = r["fused"].as_array().expect("fused");
    assert_eq!(fused.len(), dets.len());
    assert!(fused.iter().all(|f| f["frames_seen"] == 3));
    let png = annotated.join("ref_uav75-detections.png");
    let drawn = image::open(&png).expect("annotated PNG").to_rgb8();
    let original = image::open(&image).expect("image").to_rgb8();
    assert_eq!(drawn.dimensions(), original.dimensions());
    assert_ne!(drawn, original, "boxes are drawn");
}

#[test]
fn eval_detector_agrees_with_the_python_evaluation_of_the_model() {
    // The default model's metrics.json holds pycocotools' numbers for the same model and split,
    // computed at export time with onnxruntime in Python (models/detector/eval.py).
    let python: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/models/detector/crackseg-tiles/metrics.json"
        ))
        .expect("metrics.json"),
    )
    .expect("JSON");
    for dataset in ["uav75", "quaywall"] {
        let coco = format!("{}/{dataset}/val.json", cracks().display());
        let rust = ok_json(&["eval-detector", "--coco", &coco, "--json"]);
        let py = &python["pycocotools_val"][format!("320/{dataset}")];
        // Same model, contract and metric; the photos are JPEG, and PIL and the image crate's
        // decoders differ by a grey level here and there, which moves a few scores: 0.01 covers it
        // (measured: ≤ 0.007).
        for (ours, theirs) in [("map", "mAP"), ("map50", "mAP50"), ("ar100", "AR100")] {
            let (a, b) = (
                rust[ours].as_f64().expect(ours),
                py[theirs].as_f64().expect(theirs),
            );
            assert!(
                (a - b).abs() <= 0.01,
                "{dataset} {ours}: crackbot {a} vs Python {b}"
            );
        }
        assert_eq!(rust["images"], py["images"]);
        assert!(rust["ms_per_image"].as_f64().expect("ms") > 0.0);
        // uav75 has masks: the crack map is scored pixel by pixel; quaywall has boxes only.
        let pixel = rust.get("pixel").and_then(Value::as_array);
        if dataset == "uav75" {
            let pixel = pixel.expect("pixel metrics on a split with masks");
            assert_eq!(pixel.len(), 3);
            for p in pixel {
                let f1 = p["ods"]["f1"].as_f64().expect("ods f1");
                assert!(f1 > 0.0 && f1 <= 1.0, "{p}");
                let ois = p["ois_f1"].as_f64().expect("ois");
                assert!(ois > 0.0 && ois <= 1.0, "{p}");
                assert_eq!(p["at_half"]["threshold"], 0.5);
                assert_eq!(p["images"], rust["images"]);
            }
            // Pixel-exact, 2 px, 5 px: a wider tolerance forgives more.
            assert_eq!(pixel[0]["tolerance_px"], 0.0);
            for k in 1..3 {
                assert!(pixel[k]["ods"]["f1"].as_f64() >= pixel[k - 1]["ods"]["f1"].as_f64());
            }
            // Crack-level recall over the same masks.
            let c = &rust["cracks"];
            let (found, cracks) = (c["found"].as_u64(), c["cracks"].as_u64());
            assert!(found > Some(0) && found <= cracks, "{c}");
            assert_eq!(c["images"], rust["images"]);
        } else {
            assert!(pixel.is_none(), "{rust}");
        }
    }
    let classical = ok_json(&[
        "eval-detector",
        "--coco",
        &format!("{}/crackforest/val.json", cracks().display()),
        "--detector",
        "classical",
        "--json",
    ]);
    assert_eq!(classical["detector"], "classical");
    for k in ["map", "map50", "ar100"] {
        let v = classical[k].as_f64().expect(k);
        assert!((0.0..=1.0).contains(&v), "{k} = {v}");
    }
}

#[test]
fn eval_detector_on_rendered_plates_counts_cracks_found_and_decoys_proposed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let set = dir.path().join("set");
    let out = crackbot(&[
        "sim",
        "detector-set",
        "--scenes",
        "3",
        "--frames-per-scene",
        "1",
        "--seed",
        "424242",
        "--out",
        s(&set),
        "--json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let features: Value = serde_json::from_str(
        &std::fs::read_to_string(set.join("features.json")).expect("features.json"),
    )
    .expect("JSON");
    let count = |kind: &str| {
        features["images"]
            .as_array()
            .expect("images")
            .iter()
            .flat_map(|i| i["boxes"].as_array().expect("boxes").iter())
            .filter(|b| b["kind"] == kind)
            .count() as u64
    };
    let coco = set.join("annotations.json");
    let r = ok_json(&["eval-detector", "--coco", s(&coco), "--json"]);
    let scene = &r["scene"];
    assert_eq!(scene["frames"], 3);
    assert_eq!(scene["cracks"].as_u64(), Some(count("crack")));
    assert_eq!(scene["decoys"].as_u64(), Some(count("decoy")));
    let (found, cracks) = (scene["found"].as_u64().expect("found"), count("crack"));
    assert!(found <= cracks && cracks > 0);
    assert_eq!(
        scene["missed"].as_array().expect("missed").len() as u64,
        cracks - found
    );
    let by_width: u64 = scene["by_width"]
        .as_array()
        .expect("by_width")
        .iter()
        .map(|b| b["cracks"].as_u64().expect("cracks"))
        .sum();
    assert_eq!(by_width, cracks);
    // Rendered masks: pixel metrics too.
    assert_eq!(
        r["pixel"].as_array().expect("pixel").len(),
        3,
        "pixel-exact, 2 px, 5 px"
    );
    assert!(
        r["cracks"]["cracks"].as_u64() > Some(0),
        "cracks of the masks counted: {r}"
    );
    // The text report says the same.
    let out = crackbot(&["eval-detector", "--coco", s(&coco)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t = text(&out.stdout);
    assert!(t.contains(&format!("{found}/{cracks} cracks found")), "{t}");
    assert!(t.contains("ODS F1"), "{t}");
}

/// The robot's own view: a frame of the built-in default scene. Every one of its four cracks
/// (1, 2 bent, 5 partly under a screw, 10 mm) gets its own box (IoU ≥ 0.5 with the renderer's
/// exact box), with a centre line inside it, and no box swallows the plate (the previous
/// detector's failure: one box around the whole plate).
#[test]
fn detect_finds_each_crack_of_the_default_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = crackbot(&["sim", "render", "--out", s(dir.path()), "--frames", "1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let frame = dir.path().join("images/frame_0000.png");
    let truth: Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("images/frame_0000.json")).expect("frame JSON"),
    )
    .expect("JSON");
    let r = ok_json(&["detect", s(&frame), "--json"]);
    let dets = r["images"][0]["detections"].as_array().expect("detections");
    let boxes: Vec<[f64; 4]> = dets
        .iter()
        .map(|d| {
            let b: Vec<f64> = d["bbox"]
                .as_array()
                .expect("bbox")
                .iter()
                .map(|v| v.as_f64().expect("number"))
                .collect();
            [b[0], b[1], b[2], b[3]]
        })
        .collect();
    let iou = |a: [f64; 4], b: [f64; 4]| {
        let iw = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
        let ih = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
        let u = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - iw * ih;
        iw * ih / u
    };
    let cracks: Vec<&Value> = truth["boxes"]
        .as_array()
        .expect("boxes")
        .iter()
        .filter(|b| b["kind"] == "crack")
        .collect();
    assert_eq!(cracks.len(), 4);
    for c in &cracks {
        let f = |k: &str| c[k].as_f64().expect(k);
        let gt = [f("x"), f("y"), f("x") + f("w"), f("y") + f("h")];
        let best = boxes.iter().map(|b| iou(*b, gt)).fold(0.0, f64::max);
        assert!(
            best >= 0.5,
            "the {} mm crack at {gt:?} is not found (best IoU {best:.2}): {boxes:?}",
            f("width_mm")
        );
    }
    let plate_area = 560.0 * 280.0; // 200 × 100 mm at 2.8 px/mm
    for (d, b) in dets.iter().zip(&boxes) {
        assert!(
            (b[2] - b[0]) * (b[3] - b[1]) < 0.25 * plate_area,
            "a box swallows the plate: {b:?}"
        );
        assert!(d["polyline_px"].as_array().expect("polyline").len() >= 2);
    }
}

#[test]
fn detect_adds_the_box_heads_boxes_after_the_crack_maps_only_when_asked() {
    let image = format!("{REFERENCE}/ref_quaywall.png");
    let source_of = |r: &Value| -> Vec<(f64, bool)> {
        r["images"][0]["detections"]
            .as_array()
            .expect("detections")
            .iter()
            .map(|d| {
                (
                    d["score"].as_f64().expect("score"),
                    d["source"] == "box_head",
                )
            })
            .collect()
    };
    let plain = source_of(&ok_json(&[
        "detect",
        &image,
        "--threshold",
        "0.05",
        "--json",
    ]));
    let with = ok_json(&[
        "detect",
        &image,
        "--threshold",
        "0.05",
        "--box-head",
        "--json",
    ]);
    let both = source_of(&with);
    assert!(plain.iter().all(|(_, head)| !head), "{plain:?}");
    let heads = both.iter().filter(|(_, head)| *head).count();
    assert!(heads > 0, "{both:?}");
    // The crack map's detections first and unchanged, then the head's, under 0.5, best first.
    assert_eq!(&both[..plain.len()], &plain[..]);
    assert!(both[plain.len()..].iter().all(|&(s, head)| head && s < 0.5));
    assert!(both[plain.len()..].windows(2).all(|w| w[0].0 >= w[1].0));
    for d in &with["images"][0]["detections"]
        .as_array()
        .expect("detections")[plain.len()..]
    {
        assert!(
            d.get("polyline_px").is_none() && d.get("pieces_px").is_none(),
            "{d}"
        );
    }
}

#[test]
fn bad_input_is_a_named_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("missing.png");
    fails_naming(&["detect", s(&missing)], "missing.png");
    let corrupt = dir.path().join("corrupt.png");
    std::fs::write(&corrupt, b"not a png").expect("write");
    fails_naming(
        &["detect", s(&corrupt), "--detector", "classical"],
        "corrupt.png",
    );
    let image = format!("{REFERENCE}/ref_quaywall.png");
    fails_naming(&["detect", &image, "--threshold", "2"], "--threshold");
    fails_naming(&["detect", &image, "--model", s(&corrupt)], "corrupt.png");
    let pairs = dir.path().join("collinear.csv");
    write_pairs(&pairs, true);
    fails_naming(
        &[
            "homography",
            "fit",
            s(&pairs),
            "--out",
            s(&dir.path().join("c.toml")),
        ],
        "one line",
    );
    let bad_cal = dir.path().join("bad.toml");
    std::fs::write(&bad_cal, "matrix = 3").expect("write");
    fails_naming(
        &["detect", &image, "--calibration", s(&bad_cal)],
        "bad.toml",
    );
    let bad_coco = dir.path().join("bad.json");
    std::fs::write(&bad_coco, "{\"images\": 5}").expect("write");
    fails_naming(
        &[
            "eval-detector",
            "--coco",
            s(&bad_coco),
            "--detector",
            "classical",
        ],
        "bad.json",
    );
    let short = dir.path().join("short.csv");
    std::fs::write(&short, "1,2,3\n").expect("write");
    fails_naming(
        &[
            "homography",
            "fit",
            s(&short),
            "--out",
            s(&dir.path().join("d.toml")),
        ],
        "short.csv",
    );
}
