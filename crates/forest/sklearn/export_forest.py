#!/usr/bin/env python3
"""Export a scikit-learn RandomForestClassifier to the JSON read by `crackbot_forest::sklearn`.

Usage (from crates/forest/, with the venv described in README.md):

    sklearn/.venv/bin/python sklearn/export_forest.py export MODEL.joblib OUT.json
        Export a forest pickled with joblib (or pickle).

    sklearn/.venv/bin/python sklearn/export_forest.py fixture tests/fixtures
        Regenerate the test fixtures: train a small forest on synthetic MAV-like data and write
        sklearn_forest.json (the export) and sklearn_predictions.json (test rows with scikit-learn's
        predict and predict_proba).

From Python: `export_forest(clf)` returns the JSON-ready dict.

The export holds each tree's `tree_` arrays verbatim: children_left / children_right (-1 = leaf),
feature (-2 at leaves), threshold (float64) and value[:, 0, :] (class fractions since scikit-learn 1.4,
weighted counts before; the importer normalises leaf rows). Class labels must be numeric (e.g. crack widths
in mm) and are written as floats.
"""

import json
import sys

import numpy as np

FORMAT = "crackbot-sklearn-forest"
VERSION = 1


def export_forest(clf):
    """JSON-ready dict of a fitted RandomForestClassifier (single output)."""
    import sklearn

    if getattr(clf, "n_outputs_", 1) != 1:
        raise ValueError("only single-output forests are supported")
    trees = []
    for est in clf.estimators_:
        t = est.tree_
        trees.append(
            {
                "children_left": t.children_left.tolist(),
                "children_right": t.children_right.tolist(),
                "feature": t.feature.tolist(),
                "threshold": [float(v) for v in t.threshold],
                "value": t.value[:, 0, :].tolist(),
            }
        )
    return {
        "format": FORMAT,
        "version": VERSION,
        "sklearn_version": sklearn.__version__,
        "n_features": int(clf.n_features_in_),
        "classes": [float(c) for c in clf.classes_],
        "feature_importances": [float(v) for v in clf.feature_importances_],
        "trees": trees,
    }


def adc(v):
    """Like crackbot_forest::synthetic: clamp to [0, 1023], 0.1 resolution, float32."""
    return (np.round(np.clip(v, 0.0, 1023.0) * 10.0) / 10.0).astype(np.float32)


def fixture(out_dir):
    from sklearn.ensemble import RandomForestClassifier

    rng = np.random.default_rng(20240607)
    n_features, n_classes, spread = 3, 4, 60.0
    widths = np.array([0.0, 1.0, 2.0, 5.0])  # class labels in mm
    centres = rng.uniform(350.0, 850.0, size=(n_classes, n_features))

    def blobs(n):
        c = np.arange(n) % n_classes
        x = adc(centres[c] + spread * rng.standard_normal((n, n_features)))
        return x, widths[c]

    x_train, y_train = blobs(1500)
    x_test, _ = blobs(400)
    clf = RandomForestClassifier(n_estimators=20, max_depth=10, random_state=0)
    clf.fit(x_train, y_train)

    # Edge rows: features set to the float32 values around split thresholds (the nearest float32 of the
    # float64 threshold and its neighbours), where float32-vs-float64 comparison subtleties show.
    edge = []
    for est in clf.estimators_[:5]:
        t = est.tree_
        for node in np.flatnonzero(t.children_left >= 0)[:30]:
            thr = t.threshold[node]
            near = np.float32(thr)
            for v in (np.nextafter(near, np.float32(-np.inf)), near, np.nextafter(near, np.float32(np.inf))):
                row = x_test[len(edge) % len(x_test)].copy()
                row[t.feature[node]] = v
                edge.append(row)
    x_all = np.vstack([x_test, np.array(edge, dtype=np.float32)]).astype(np.float32)

    export = export_forest(clf)
    with open(f"{out_dir}/sklearn_forest.json", "w") as f:
        json.dump(export, f, separators=(",", ":"))
    preds = {
        "sklearn_version": export["sklearn_version"],
        "n_features": n_features,
        "n_edge_rows": len(edge),
        "x": [float(v) for v in x_all.ravel()],
        "predict": [float(v) for v in clf.predict(x_all)],
        "predict_proba": clf.predict_proba(x_all).tolist(),
    }
    with open(f"{out_dir}/sklearn_predictions.json", "w") as f:
        json.dump(preds, f, separators=(",", ":"))
    n_nodes = sum(e.tree_.node_count for e in clf.estimators_)
    print(f"wrote {out_dir}: {len(clf.estimators_)} trees, {n_nodes} nodes, {len(x_all)} test rows "
          f"({len(edge)} at thresholds)")


def main(argv):
    if len(argv) == 3 and argv[0] == "export":
        import joblib

        clf = joblib.load(argv[1])
        with open(argv[2], "w") as f:
            json.dump(export_forest(clf), f, separators=(",", ":"))
    elif len(argv) == 2 and argv[0] == "fixture":
        fixture(argv[1])
    else:
        print(__doc__, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
