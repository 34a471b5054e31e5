//! Import of a scikit-learn `RandomForestClassifier` exported to JSON by `sklearn/export_forest.py`.
//!
//! JSON layout (`"format": "crackbot-sklearn-forest"`, `"version": 1`):
//!
//! ```json
//! { "format": "crackbot-sklearn-forest", "version": 1, "sklearn_version": "1.9.1",
//!   "n_features": 3, "classes": [0.0, 1.0, 2.0, 3.0], "feature_importances": [0.3, 0.3, 0.4],
//!   "trees": [ { "children_left": [1, -1, -1], "children_right": [2, -1, -1],
//!                "feature": [0, -2, -2], "threshold": [512.35, -2.0, -2.0],
//!                "value": [[0.5, 0.5, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]] } ] }
//! ```
//!
//! These are the `estimator.tree_` arrays verbatim (`value` as `value[:, 0, :]`; `-1` marks a leaf). Leaf
//! rows of `value` are normalised to sum 1 (scikit-learn ≥ 1.4 already stores fractions; older versions
//! store weighted counts), and the tree is re-laid out in depth-first pre-order.
//!
//! Thresholds: scikit-learn compares `float32` features with `float64` thresholds (`X[i, f] <= t64` in
//! double). Each threshold is rounded **down** to the largest `f32 <= t64`; then `x <= t32 ⟺ x <= t64` for
//! every `f32` x, so the imported forest makes exactly scikit-learn's decisions.

use std::path::Path;

use serde::Deserialize;

use crate::error::{ForestError, Result};
use crate::flat::{round_down_f32, Node};
use crate::forest::RandomForest;

/// `format` value of the JSON export.
pub const JSON_FORMAT: &str = "crackbot-sklearn-forest";
/// Export versions this build reads.
pub const JSON_VERSIONS: &[u32] = &[1];

#[derive(Deserialize)]
struct Export {
    format: String,
    version: u32,
    n_features: usize,
    classes: Vec<f64>,
    #[serde(default)]
    feature_importances: Option<Vec<f64>>,
    trees: Vec<ExportTree>,
}

#[derive(Deserialize)]
struct ExportTree {
    children_left: Vec<i64>,
    children_right: Vec<i64>,
    feature: Vec<i64>,
    threshold: Vec<f64>,
    value: Vec<Vec<f64>>,
}

/// Imports a forest from the JSON text of `export_forest.py`.
pub fn import_json_str(json: &str) -> Result<RandomForest> {
    import(json).map_err(|message| ForestError::SklearnImport {
        path: None,
        message,
    })
}

/// Imports a forest from a JSON file written by `export_forest.py`; errors name the file.
pub fn import_json_file(path: impl AsRef<Path>) -> Result<RandomForest> {
    let path = path.as_ref();
    let err = |message: String| ForestError::SklearnImport {
        path: Some(path.to_path_buf()),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
    import(&text).map_err(err)
}

fn import(json: &str) -> std::result::Result<RandomForest, String> {
    let e: Export = serde_json::from_str(json).map_err(|e| format!("JSON: {e}"))?;
    if e.format != JSON_FORMAT {
        return Err(format!("format {:?}, expected {JSON_FORMAT:?}", e.format));
    }
    if !JSON_VERSIONS.contains(&e.version) {
        return Err(format!(
            "unsupported export version {} (supported: {JSON_VERSIONS:?})",
            e.version
        ));
    }
    let k = e.classes.len();
    if k == 0 {
        return Err("no classes".into());
    }
    if e.trees.is_empty() {
        return Err("no trees".into());
    }
    let mut nodes: Vec<Node> = Vec::new();
    let mut offsets = vec![0u32];
    let mut leaf_values: Vec<f32> = Vec::new();
    for (t, tree) in e.trees.iter().enumerate() {
        convert_tree(tree, e.n_features, k, &mut nodes, &mut leaf_values)
            .map_err(|m| format!("tree {t}: {m}"))?;
        offsets.push(u32::try_from(nodes.len()).map_err(|_| "too many nodes".to_string())?);
    }
    RandomForest::from_parts(
        e.n_features,
        e.classes,
        nodes,
        offsets,
        leaf_values,
        e.feature_importances,
    )
    .map_err(|err| err.to_string())
}

fn convert_tree(
    tree: &ExportTree,
    n_features: usize,
    k: usize,
    nodes: &mut Vec<Node>,
    leaf_values: &mut Vec<f32>,
) -> std::result::Result<(), String> {
    let n = tree.children_left.len();
    if n == 0 {
        return Err("empty tree".into());
    }
    if [
        tree.children_right.len(),
        tree.feature.len(),
        tree.threshold.len(),
        tree.value.len(),
    ] != [n; 4]
    {
        return Err("arrays of different lengths".into());
    }
    let index = |v: i64| usize::try_from(v).ok().filter(|&i| i < n);
    let mut visited = vec![false; n];
    // (sklearn node, index of the parent whose right child this is)
    let mut stack: Vec<(usize, Option<usize>)> = vec![(0, None)];
    while let Some((s, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[s], true) {
            return Err(format!("node {s} is reached twice (not a tree)"));
        }
        let id = nodes.len();
        if let Some(p) = parent {
            nodes[p].right = u32::try_from(id).map_err(|_| "too many nodes".to_string())?;
        }
        let (l, r) = (tree.children_left[s], tree.children_right[s]);
        if l == -1 && r == -1 {
            let v = &tree.value[s];
            if v.len() != k {
                return Err(format!("node {s}: {} values for {k} classes", v.len()));
            }
            let sum: f64 = v.iter().sum();
            if !(sum > 0.0 && sum.is_finite()) || v.iter().any(|x| *x < 0.0) {
                return Err(format!("node {s}: invalid leaf values {v:?}"));
            }
            let leaf = (leaf_values.len() / k) as u32;
            leaf_values.extend(v.iter().map(|x| (x / sum) as f32));
            nodes.push(Node::leaf(leaf));
            continue;
        }
        let (Some(li), Some(ri)) = (index(l), index(r)) else {
            return Err(format!(
                "node {s}: child index {l} / {r} out of range 0..{n}"
            ));
        };
        let f = tree.feature[s];
        if f < 0 || f as usize >= n_features {
            return Err(format!(
                "node {s}: feature {f} out of range 0..{n_features}"
            ));
        }
        let t = tree.threshold[s];
        if t.is_nan() {
            return Err(format!("node {s}: NaN threshold"));
        }
        nodes.push(Node {
            feature: f as u32,
            threshold: round_down_f32(t),
            right: 0,
        });
        stack.push((ri, Some(id)));
        stack.push((li, None));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Classifier;

    const ONE: &str = r#"{"format": "crackbot-sklearn-forest", "version": 1, "sklearn_version": "x",
        "n_features": 2, "classes": [0.0, 2.5],
        "trees": [{"children_left": [1, -1, -1], "children_right": [2, -1, -1], "feature": [1, -2, -2],
                   "threshold": [0.1, -2.0, -2.0], "value": [[3, 1], [3, 0], [0, 1]]}]}"#;

    #[test]
    fn imports_and_rounds_down() {
        let f = import_json_str(ONE).unwrap();
        assert_eq!(f.class_labels(), &[0.0, 2.5]);
        // 0.1f32 > 0.1f64, so x = 0.1f32 must go right, like scikit-learn.
        assert_eq!(f.predict(&[0.0, 0.1f32]), 1);
        assert_eq!(f.predict(&[0.0, 0.099_999_99]), 0);
        assert_eq!(f.predict_label(&[0.0, 1.0]), 2.5);
    }

    #[test]
    fn rejects_bad_exports() {
        for (from, to) in [
            ("\"version\": 1", "\"version\": 7"),
            (
                "[1, -1, -1], \"children_right\"",
                "[0, -1, -1], \"children_right\"",
            ),
            ("[2, -1, -1]", "[9, -1, -1]"),
            ("[1, -2, -2]", "[2, -2, -2]"),
            ("[0, 1]]", "[0, 1, 5]]"),
            ("crackbot-sklearn-forest", "other"),
            ("[0.0, 2.5]", "[]"),
        ] {
            let bad = ONE.replace(from, to);
            assert_ne!(bad, ONE, "{from}");
            let err = import_json_str(&bad).unwrap_err();
            assert!(matches!(err, ForestError::SklearnImport { .. }), "{err}");
        }
        assert!(import_json_str("{").is_err());
        let err = import_json_file("/nonexistent/forest.json").unwrap_err();
        assert!(
            err.to_string().contains("/nonexistent/forest.json"),
            "{err}"
        );
    }
}
