#!/usr/bin/env python3
"""Medians and ratios of `cargo bench --bench tactile` from criterion's estimates (including the
`onnx_runtime` group: ours vs ONNX Runtime on the same forest), next to the numbers of
`benches/sklearn_ort.py` when `benches/out/sklearn_ort.json` exists, and the training-time comparison
when `benches/out/ours_fit.json` (example `fit_csv`) and `benches/out/sklearn_fit.json`
(`benches/sklearn_fit.py`) exist.

    python3 benches/summary.py [CRITERION_DIR] [SKLEARN_ORT_JSON]

CRITERION_DIR defaults to `$CARGO_TARGET_DIR/criterion` or `target/criterion`.
"""

import json
import os
import sys
from pathlib import Path


# Depth caps of benches/tactile.rs's `per_window_depth_capped` forests.
DEPTH_CAPS = [8, 10, 12]


def median_ns(root, group, name):
    if not (root / group).is_dir():
        return None
    for d in (root / group).iterdir():
        bench = d / "new" / "benchmark.json"
        if bench.exists() and json.loads(bench.read_text()).get("function_id") == name:
            return json.loads((d / "new" / "estimates.json").read_text())["median"]["point_estimate"]
    return None


def throughput(root, group, name):
    """Elements per iteration of a criterion benchmark, when it set a throughput."""
    for d in (root / group).iterdir() if (root / group).is_dir() else []:
        bench = d / "new" / "benchmark.json"
        if bench.exists():
            b = json.loads(bench.read_text())
            if b.get("function_id") == name:
                return (b.get("throughput") or {}).get("Elements")
    return None


def onnx_runtime(root):
    """The `onnx_runtime` group: ours vs ONNX Runtime on the same forest and windows, same run."""
    m = {n: median_ns(root, "onnx_runtime", n) for n in ["ours_row", "onnxruntime_row", "ours_batch", "onnxruntime_batch"]}
    if not m["ours_row"]:
        return
    print("ours vs ONNX Runtime (onnx_runtime group: same forest file and windows, one core, 1 intra-op thread)")
    if m["onnxruntime_row"]:
        print(f"  one window: ours {m['ours_row'] / 1e3:.2f} µs, ONNX Runtime {m['onnxruntime_row'] / 1e3:.2f} µs "
              f"= {m['onnxruntime_row'] / m['ours_row']:.1f}× ours")
    n = throughput(root, "onnx_runtime", "ours_batch")
    if n and m["ours_batch"] and m["onnxruntime_batch"]:
        ours, theirs = n / (m["ours_batch"] / 1e9), n / (m["onnxruntime_batch"] / 1e9)
        print(f"  batch of {n} windows: ours {ours:.0f} windows/s, ONNX Runtime {theirs:.0f} windows/s "
              f"(ours {ours / theirs:.1f}×)")


def training(out):
    """Training time, ours (`fit_csv`) vs scikit-learn (`sklearn_fit.py`), from their JSON files."""
    ours_p, skl_p = out / "ours_fit.json", out / "sklearn_fit.json"
    if not (ours_p.exists() and skl_p.exists()):
        return
    ours, skl = json.loads(ours_p.read_text()), json.loads(skl_p.read_text())
    print(f"training {ours['trees']} trees on {ours['rows']} windows ({ours['csv']}), median wall time")
    print(f"  ours {ours['threads']} threads: {ours['fit_median_s']:.2f} s ({ours['nodes']} nodes); "
          f"scikit-learn {skl['sklearn_version']} n_jobs={skl['n_jobs']}: {skl['fit_median_s']:.2f} s "
          f"({skl['nodes']} nodes); scikit-learn / ours = {skl['fit_median_s'] / ours['fit_median_s']:.1f}×")
    if ours["csv"] != skl["csv"] or ours["rows"] != skl["rows"]:
        print(f"  warning: different inputs ({ours['csv']}, {ours['rows']} rows vs {skl['csv']}, {skl['rows']} rows)")


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else
                Path(os.environ.get("CARGO_TARGET_DIR", "target")) / "criterion")
    skl = Path(sys.argv[2] if len(sys.argv) > 2 else "benches/out/sklearn_ort.json")
    n_test = None
    m = {}
    for group, name in [("per_window", "stream_push"), ("per_window", "forest_predict"),
                        ("per_window", "stream_push+forest_predict"), ("batch", "predict_batch"),
                        ("linfa_forest", "linfa_predict_row"), ("linfa_forest", "flat_predict_row"),
                        ("linfa_forest", "linfa_predict_batch"), ("linfa_forest", "flat_predict_batch")]:
        m[name] = median_ns(root, group, name)
    for d in DEPTH_CAPS:
        m[f"depth{d}/stream_push+forest_predict"] = median_ns(
            root, "per_window_depth_capped", f"depth{d}/stream_push+forest_predict")
        m[f"depth{d}/predict_batch"] = median_ns(root, "batch", f"depth{d}/predict_batch")
    onnx_runtime(root)
    training(skl.parent)
    ext = json.loads(skl.read_text()) if skl.exists() else {}
    n_test = ext.get("n_test")

    def us(name):
        return f"{m[name] / 1e3:10.3f} µs" if m.get(name) else "       n/a"

    print("median latency per window (one core)")
    for name in ["stream_push", "forest_predict", "stream_push+forest_predict", "linfa_predict_row",
                 "flat_predict_row"]:
        print(f"  {name:30s} {us(name)}")
    for d in DEPTH_CAPS:
        print(f"  {'depth ≤ ' + str(d) + ': stream_push+forest_predict':42s} "
              f"{us(f'depth{d}/stream_push+forest_predict')}")
    if m.get("linfa_predict_row") and m.get("flat_predict_row"):
        print(f"  linfa / flat, same forest, one row: {m['linfa_predict_row'] / m['flat_predict_row']:.1f}×")
    if n_test:
        print(f"batch throughput ({n_test} windows)")
        for name in ["predict_batch"] + [f"depth{d}/predict_batch" for d in DEPTH_CAPS] + [
                "linfa_predict_batch", "flat_predict_batch"]:
            if m.get(name):
                print(f"  {name:30s} {n_test / (m[name] / 1e9):12.0f} windows/s")
        if m.get("linfa_predict_batch") and m.get("flat_predict_batch"):
            print(f"  flat / linfa, same forest, batch: {m['linfa_predict_batch'] / m['flat_predict_batch']:.1f}×")
    if ext and m.get("forest_predict"):
        ours = m["forest_predict"] / 1e3
        print("scikit-learn / ONNX Runtime (benches/sklearn_ort.py, their own 100-tree forest on the same windows)")
        print(f"  sklearn one row {ext['sklearn_row_us']:.1f} µs = {ext['sklearn_row_us'] / ours:.0f}× ours; "
              f"ORT one row {ext['ort_row_us']:.2f} µs = {ext['ort_row_us'] / ours:.1f}× ours")
        if m.get("predict_batch"):
            ours_b = n_test / (m["predict_batch"] / 1e9)
            print(f"  sklearn batch {ext['sklearn_batch_windows_per_s']:.0f} windows/s, ORT batch "
                  f"{ext['ort_batch_windows_per_s']:.0f} windows/s, ours {ours_b:.0f} windows/s "
                  f"({ours_b / ext['sklearn_batch_windows_per_s']:.1f}× sklearn, "
                  f"{ours_b / ext['ort_batch_windows_per_s']:.1f}× ORT)")


if __name__ == "__main__":
    main()
