#!/usr/bin/env python3
"""scikit-learn and ONNX Runtime on the windows of `benches/tactile.rs`, for comparison with our forest.

The windows are the authors' real recordings (surface-type experiment, MAV of D1, D2, P over 10-sample
windows every 2 samples): repetition 1 trains, repetition 2 is predicted. They are exported by a Rust
example so both sides see the same rows::

    cargo run --release -p crackbot-research --example export_windows -- benches/out
    bash benches/setup_venv.sh                   # benches/.venv-bench (ignored), benches/requirements.txt
    taskset -c 1 benches/.venv-bench/bin/python benches/sklearn_ort.py benches/out

It trains `RandomForestClassifier(n_estimators=100, random_state=1)` (fully grown trees, sqrt(3) = 1
feature per split: the same parameters as our `ForestParams::classifier()`), then times on one thread:

* scikit-learn `predict` on one row (a 1×3 array), median over repeated calls;
* scikit-learn `predict` on all test windows (`n_jobs=1`), in windows/s;
* ONNX Runtime's `TreeEnsembleClassifier` (the forest converted by skl2onnx, one intra-op thread) on one
  row and on all windows.

Medians go to stdout and to `OUT/sklearn_ort.json`.
"""

import json
import sys
import time
from pathlib import Path

import numpy as np


def load(path):
    data = np.loadtxt(path, delimiter=",", skiprows=1, dtype=np.float64)
    return np.ascontiguousarray(data[:, :-1], dtype=np.float32), data[:, -1].astype(np.int64)


def median_ns(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter_ns()
        fn()
        times.append(time.perf_counter_ns() - t0)
    return float(np.median(times))


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "benches/out")
    x_train, y_train = load(out / "train.csv")
    x_test, y_test = load(out / "test.csv")
    n_test = len(x_test)

    import onnxruntime as ort
    import sklearn
    from skl2onnx import convert_sklearn
    from skl2onnx.common.data_types import FloatTensorType
    from sklearn.ensemble import RandomForestClassifier

    t0 = time.perf_counter()
    clf = RandomForestClassifier(n_estimators=100, random_state=1, n_jobs=1).fit(x_train, y_train)
    train_s = time.perf_counter() - t0
    nodes = sum(t.tree_.node_count for t in clf.estimators_)
    acc = float((clf.predict(x_test) == y_test).mean())
    print(f"scikit-learn {sklearn.__version__}: trained in {train_s:.1f} s on {len(x_train)} windows, "
          f"{nodes} nodes, test accuracy {acc:.4f} on {n_test} windows")

    res = {"n_test": n_test, "sklearn_version": sklearn.__version__, "ort_version": ort.__version__}
    rows = [x_test[i:i + 1] for i in range(0, n_test, max(1, n_test // 1000))]
    k = [0]

    def one(predict):
        def f():
            predict(rows[k[0] % len(rows)])
            k[0] += 1
        return f

    res["sklearn_row_us"] = median_ns(one(clf.predict), 300) / 1e3
    batch_ns = median_ns(lambda: clf.predict(x_test), 5)
    res["sklearn_batch_windows_per_s"] = n_test / (batch_ns / 1e9)

    onx = convert_sklearn(clf, initial_types=[("x", FloatTensorType([None, 3]))],
                          options={id(clf): {"zipmap": False}}, target_opset={"": 17, "ai.onnx.ml": 3})
    so = ort.SessionOptions()
    so.intra_op_num_threads = 1
    so.inter_op_num_threads = 1
    sess = ort.InferenceSession(onx.SerializeToString(), so, providers=["CPUExecutionProvider"])
    name = sess.get_inputs()[0].name
    ort_pred = sess.run(None, {name: x_test})[0]
    res["ort_agrees_with_sklearn"] = float((ort_pred == clf.predict(x_test)).mean())
    res["ort_row_us"] = median_ns(one(lambda r: sess.run(None, {name: r})), 3000) / 1e3
    batch_ns = median_ns(lambda: sess.run(None, {name: x_test}), 5)
    res["ort_batch_windows_per_s"] = n_test / (batch_ns / 1e9)

    print(f"scikit-learn predict, one row:     median {res['sklearn_row_us']:9.1f} µs")
    print(f"scikit-learn predict, {n_test} rows: {res['sklearn_batch_windows_per_s']:12.0f} windows/s")
    print(f"ONNX Runtime {ort.__version__}, one row:   median {res['ort_row_us']:9.1f} µs")
    print(f"ONNX Runtime, {n_test} rows:         {res['ort_batch_windows_per_s']:12.0f} windows/s "
          f"(agrees with scikit-learn on {res['ort_agrees_with_sklearn']:.4%})")
    (out / "sklearn_ort.json").write_text(json.dumps(res, indent=2) + "\n")


if __name__ == "__main__":
    main()
