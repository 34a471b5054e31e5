//! The COCO metrics of `crackbot_vision::coco::evaluate` against the real pycocotools (2.0.10) on the
//! real validation splits, with synthetic detections (`tests/fixtures/make_coco_fixtures.py`).

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::PathBuf;

use crackbot_vision::coco::{evaluate, load_results, CocoDataset, CocoMetrics};

fn data(rel: &str) -> PathBuf {
    crackbot_datasets::require(crackbot_datasets::CRACKS).join(rel)
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures")).join(name)
}

fn check(name: &str, gt_rel: &str) -> f64 {
    let gt = CocoDataset::load(data(gt_rel)).unwrap();
    let dets = load_results(fixture(&format!("{name}_dets.json")), &gt).unwrap();
    let expected: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(fixture(&format!("{name}_metrics.json"))).unwrap(),
    )
    .unwrap();
    let got = evaluate(&gt, &dets).unwrap();
    let mut worst = 0.0f64;
    for (n, v) in CocoMetrics::NAMES.iter().zip(got.stats()) {
        let want = expected["metrics"][n].as_f64().unwrap();
        let dev = (v - want).abs();
        assert!(dev < 1e-3, "{name} {n}: ours {v}, pycocotools {want}");
        worst = worst.max(dev);
    }
    // The ground truth against itself gives AP 1, as the dataset README says.
    let perfect = evaluate(&gt, &gt.ground_truth_as_results()).unwrap();
    assert!((perfect.map - 1.0).abs() < 1e-12, "{name}");
    assert!((perfect.ar100 - 1.0).abs() < 1e-12, "{name}");
    println!("{name}: max deviation from pycocotools {worst:e}");
    worst
}

#[test]
fn crackforest_matches_pycocotools() {
    assert!(check("crackforest", "crackforest/val.json") < 1e-9);
}

#[test]
fn uav75_matches_pycocotools() {
    assert!(check("uav75", "uav75/val.json") < 1e-9);
}

#[test]
fn quaywall_matches_pycocotools() {
    assert!(check("quaywall", "quaywall/val.json") < 1e-9);
}

#[test]
fn val_all_matches_pycocotools() {
    assert!(check("val_all", "val_all.json") < 1e-9);
}
