"""Gathers the training summaries (runs/train*/summary.json) and the pycocotools metrics
(out/metrics_*.json, written by eval.py in train.sh) into metrics.json, which the model card quotes
and crackbot's CLI test compares its own evaluation with."""
from __future__ import annotations

import argparse
import glob
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def load(path):
    with open(path) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", default=os.path.join(HERE, "runs"))
    ap.add_argument("--eval", default=os.path.join(HERE, "out"))
    ap.add_argument("--out", default=os.path.join(HERE, "metrics.json"))
    a = ap.parse_args()
    out = {"training": {}, "pycocotools_val": {}}
    for run in sorted(glob.glob(os.path.join(a.runs, "*", "summary.json"))):
        out["training"][os.path.basename(os.path.dirname(run))] = load(run)
    for size in (320, 256, 416):
        for name in ("crackforest", "uav75", "quaywall", "val_all"):
            p = os.path.join(a.eval, f"metrics_{size}_{name}.json")
            if os.path.exists(p):
                out["pycocotools_val"][f"{size}/{name}"] = load(p)
    aug = os.path.join(a.eval, "metrics_320_augval.json")
    if os.path.exists(aug):
        out["pycocotools_augmented_val_seed0_320"] = load(aug)
    with open(a.out, "w") as f:
        json.dump(out, f, indent=1)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
