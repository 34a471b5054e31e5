#!/usr/bin/env python3
"""Training time of scikit-learn's `RandomForestClassifier` on a CSV of windows, next to ours
(`cargo run --release -p crackbot-research --example fit_csv` on the same CSV and the same cores):

    bash benches/setup_venv.sh                                    # benches/.venv-bench, pinned
    benches/.venv-bench/bin/python benches/sklearn_fit.py benches/out/train.csv \\
        --jobs 2 --repeats 5 --json benches/out/sklearn_fit.json
    python3 benches/summary.py                                    # the ratio

The CSV has a header line, then one window per line: the features, then the class in the last column
(`crackbot-tactile`'s example `export_windows` writes them). The forest has our defaults:
`n_estimators=100` (or `--trees`), fully grown, sqrt(n_features) features per split, bootstrap,
`random_state=1`, `n_jobs=--jobs`. The median wall time of `--repeats` fits is printed and written to
`--json` with every run's time.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("csv", type=Path)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--trees", type=int, default=100)
    p.add_argument("--json", type=Path)
    a = p.parse_args()

    import sklearn
    from sklearn.ensemble import RandomForestClassifier

    data = np.loadtxt(a.csv, delimiter=",", skiprows=1, dtype=np.float64, ndmin=2)
    x = np.ascontiguousarray(data[:, :-1], dtype=np.float32)
    y = data[:, -1].astype(np.int64)
    times = []
    for _ in range(a.repeats):
        clf = RandomForestClassifier(n_estimators=a.trees, random_state=1, n_jobs=a.jobs)
        t0 = time.perf_counter()
        clf.fit(x, y)
        times.append(time.perf_counter() - t0)
    nodes = sum(t.tree_.node_count for t in clf.estimators_)
    median = float(np.median(times))
    print(f"scikit-learn {sklearn.__version__}: {a.trees} trees on {len(x)} rows × {x.shape[1]} features, "
          f"{len(np.unique(y))} classes, n_jobs={a.jobs}: median {median:.3f} s over {a.repeats} runs "
          f"{[round(t, 3) for t in times]}; {nodes} nodes")
    if a.json:
        a.json.write_text(json.dumps({
            "csv": str(a.csv), "rows": len(x), "n_features": int(x.shape[1]), "trees": a.trees,
            "n_jobs": a.jobs, "fit_s": times, "fit_median_s": median, "nodes": int(nodes),
            "sklearn_version": sklearn.__version__,
        }, indent=2) + "\n")


if __name__ == "__main__":
    main()
