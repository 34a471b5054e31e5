"""How a component's score is computed, compared on the TRAIN split (not val): the mean probability of its crack
cells (what the contract uses), their max, the mean scaled down for short components, and boxes from several map
thresholds together. Prints COCO mAP@0.5 / AR@100 of each variant per dataset.

  .venv/bin/python analysis/scoring.py --model crack-detector-320.onnx
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import coco_metrics, load_rgb, ort_runner  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))


def dedupe(dets, iou_max=0.9):
    keep = []
    for d in sorted(dets, key=lambda d: -d[4]):
        if all(contract_iou(d, k) <= iou_max for k in keep):
            keep.append(d)
    return keep[:contract.MAX_DETECTIONS]


def contract_iou(a, b):
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    u = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / u if u > 0 else 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--split", default="train")
    a = ap.parse_args()
    run, size = ort_runner(a.model)
    for ds in ("crackforest", "uav75", "quaywall"):
        coco = json.load(open(os.path.join(DATA, ds, f"{a.split}.json")))
        res = {k: [] for k in ("mean", "max", "mean_x_length", "multi_threshold")}
        for im in coco["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            h, w = img.shape[:2]
            x, _ = contract.letterbox(img, size)
            prob = run(x)[0, 0]
            base = contract.map_to_detections(prob, w, h, size)
            pimg = contract.map_to_image(prob, w, h, size)
            variants = {"mean": base}
            mx = []
            for d in base:
                cut = pimg[int(d[1]):int(np.ceil(d[3])), int(d[0]):int(np.ceil(d[2]))]
                mx.append(d[:4] + (float(cut.max()) if cut.size else d[4],))
            variants["max"] = mx
            diag = 0.15 * max(w, h)
            variants["mean_x_length"] = [d[:4] + (d[4] * min(1.0, np.hypot(d[2] - d[0], d[3] - d[1]) / diag) ** 0.5,)
                                         for d in base]
            multi = []
            for t in (0.3, 0.5, 0.7):
                multi += contract.map_to_detections(prob, w, h, size, threshold=t)
            variants["multi_threshold"] = dedupe(multi)
            for k, dets in variants.items():
                for x0, y0, x1, y1, sc in dets:
                    res[k].append({"image_id": im["id"], "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0],
                                   "score": sc})
        for k, r in res.items():
            m = coco_metrics(coco, r)
            print(f"{a.split} {ds:12s} {k:16s} mAP50 {m['mAP50']:.3f}  AR100 {m['AR100']:.3f}  mAP {m['mAP']:.3f}")


if __name__ == "__main__":
    main()
