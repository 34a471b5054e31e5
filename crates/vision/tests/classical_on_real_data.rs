//! The classical baseline on the real validation splits, scored with the COCO metrics: it runs end to
//! end on real images (JPEG decoding, `detect_dataset`, `evaluate`) and finds something. The numbers
//! are printed (`-- --nocapture`), and only loosely asserted.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::PathBuf;

use crackbot_vision::classical::ClassicalDetector;
use crackbot_vision::coco::{detect_dataset, evaluate, CocoDataset, CocoMetrics};

fn run(name: &str) -> CocoMetrics {
    let root: PathBuf = crackbot_datasets::require(crackbot_datasets::CRACKS);
    let gt = CocoDataset::load(root.join(name).join("val.json")).unwrap();
    let mut det = ClassicalDetector::default();
    let mut calls = 0;
    let results = detect_dataset(&mut det, &gt, &root.join(name), 1, |p| {
        assert_eq!(p.total, gt.images.len());
        calls += 1;
    })
    .unwrap();
    assert_eq!(calls, gt.images.len() + 1);
    let m = evaluate(&gt, &results).unwrap();
    println!(
        "{name}: {} detections on {} images, mAP {:.3}, mAP50 {:.3}, AR100 {:.3}",
        results.len(),
        gt.images.len(),
        m.map,
        m.map50,
        m.ar100
    );
    m
}

#[test]
fn classical_detector_on_crackforest_val() {
    let m = run("crackforest");
    assert!(m.map50 > 0.2, "{m:?}");
}

#[test]
fn classical_detector_on_all_val_splits() {
    let mean50: f64 = ["crackforest", "uav75", "quaywall"]
        .iter()
        .map(|n| run(n).map50)
        .sum::<f64>()
        / 3.0;
    println!("mean mAP50 {mean50:.3}");
    assert!(mean50 > 0.1);
}
