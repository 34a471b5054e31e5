"""Failure analysis, part 1: what the box rule gives from a *perfect* crack map at the model's resolution.

The ground-truth mask of each val image is turned into the map the model is trained to predict (canvas cells at
stride 2 that hold a crack pixel), then into boxes by the same rule (contract.map_to_detections); the mAP of
those boxes is the ceiling of the crack-map approach on that split: what is lost there is lost by resolution and
the rule, not by the model.

  .venv/bin/python analysis/oracle.py [--size 320]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import coco_metrics  # noqa: E402
from train import DATA, mask_to_canvas  # noqa: E402


def oracle_map(mask, w, h, size):
    s, nw, nh = contract.letterbox_params(w, h, size)
    cm = np.zeros((size, size), dtype=np.uint8)
    cm[:nh, :nw] = mask_to_canvas(mask, nw, nh)
    k = contract.STRIDE
    return cm.reshape(size // k, k, size // k, k).max((1, 3)).astype(np.float32)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=320)
    a = ap.parse_args()
    out = {}
    for ds in ("crackforest", "uav75"):
        coco = json.load(open(os.path.join(DATA, ds, "val.json")))
        res = []
        for im in coco["images"]:
            m = (np.asarray(Image.open(os.path.join(DATA, ds, im["mask_file"])).convert("L")) > 0).astype(np.uint8)
            prob = oracle_map(m, im["width"], im["height"], a.size)
            for x0, y0, x1, y1, sc in contract.map_to_detections(prob, im["width"], im["height"], a.size):
                res.append({"image_id": im["id"], "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0],
                            "score": 1.0})
        met = coco_metrics(coco, res)
        out[ds] = {k: met[k] for k in ("mAP", "mAP50", "AR100", "boxes", "detections")}
        print(ds, out[ds])
    print(json.dumps(out))


if __name__ == "__main__":
    main()
