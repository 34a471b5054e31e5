//! Import of a scikit-learn forest (fixtures written by `sklearn/export_forest.py fixture tests/fixtures`,
//! scikit-learn 1.9.1): every test row's prediction must equal scikit-learn's, probabilities within 1e-6.

#![expect(
    clippy::unwrap_used,
    reason = "a test stops at the first thing it did not expect, and says where"
)]

use std::path::PathBuf;

use crackbot_forest::{sklearn, Classifier, RandomForest};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn predictions_match_scikit_learn_on_every_row() {
    let forest = sklearn::import_json_file(fixture("sklearn_forest.json")).unwrap();
    let expected: Value = serde_json::from_str(
        &std::fs::read_to_string(fixture("sklearn_predictions.json")).unwrap(),
    )
    .unwrap();
    let nf = expected["n_features"].as_u64().unwrap() as usize;
    let x: Vec<f32> = f64s(&expected["x"]).iter().map(|&v| v as f32).collect();
    let labels = f64s(&expected["predict"]);
    let probas: Vec<Vec<f64>> = expected["predict_proba"]
        .as_array()
        .unwrap()
        .iter()
        .map(f64s)
        .collect();
    let n = labels.len();
    assert_eq!(x.len(), n * nf);
    assert_eq!(forest.n_features(), nf);
    assert_eq!(forest.n_trees(), 20);
    assert_eq!(forest.class_labels(), &[0.0, 1.0, 2.0, 5.0]);

    let mut batch = vec![0u32; n];
    forest.predict_batch(&x, nf, &mut batch).unwrap();
    let mut max_diff = 0f64;
    for i in 0..n {
        let row = &x[i * nf..(i + 1) * nf];
        let class = forest.predict(row);
        assert_eq!(
            forest.class_labels()[class as usize],
            labels[i],
            "row {i} {row:?}"
        );
        assert_eq!(forest.predict_label(row), labels[i], "row {i}");
        assert_eq!(batch[i], class, "row {i}");
        let p = forest.predict_proba(row);
        for (a, b) in p.iter().zip(&probas[i]) {
            max_diff = max_diff.max((*a as f64 - b).abs());
        }
    }
    println!(
        "{n} rows ({} at thresholds): classes equal, max |Δp| = {max_diff:.2e}",
        expected["n_edge_rows"]
    );
    assert!(max_diff < 1e-6, "max probability difference {max_diff}");

    // The imported model survives our own file format unchanged.
    let again = RandomForest::from_bytes(&forest.to_bytes()).unwrap();
    assert_eq!(again, forest);
}

#[test]
fn fixture_exercises_float32_threshold_rounding() {
    // Many float64 thresholds lie between two float32 values and round *up* to the nearest float32; with
    // round-to-nearest, a feature equal to that float32 would go left instead of right (as in sklearn).
    let export: Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("sklearn_forest.json")).unwrap())
            .unwrap();
    let mut rounds_up = 0;
    for tree in export["trees"].as_array().unwrap() {
        let left = tree["children_left"].as_array().unwrap();
        for (i, t) in f64s(&tree["threshold"]).into_iter().enumerate() {
            if left[i].as_i64() != Some(-1) && (t as f32) as f64 > t {
                rounds_up += 1;
            }
        }
    }
    assert!(rounds_up > 100, "{rounds_up}");
    // The import keeps every split node.
    let forest = sklearn::import_json_file(fixture("sklearn_forest.json")).unwrap();
    let inner = forest.nodes().iter().filter(|n| !n.is_leaf()).count();
    let inner_sklearn: usize = export["trees"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            t["children_left"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|c| c.as_i64() != Some(-1))
                .count()
        })
        .sum();
    assert_eq!(inner, inner_sklearn);
}
