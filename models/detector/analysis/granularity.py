"""Would the crack map's components at finer groupings, appended below the shipped boxes, find the boxes the rule
and the box head miss? An analysis, not shipped.

AR@100 on the photos' val split is 58.9 % with the shipped boxes (the rule's components, then the box head's):
quaywall's hand-drawn chains of small boxes along one crack and uav75's hairline pieces are still missed. The rule
dilates the crack cells by round(0.02 * max(W, H)) image pixels before grouping; a smaller radius (or none) cuts
each component into the pieces a person would box one by one. This appends, below every shipped box (scores
scaled into [0, 0.01)), the components at smaller dilation radii, each dropped where it repeats a box already
there (IoU > 0.9), and compares pycocotools mAP@0.5 / AR@100 per set on the train split (where a variant is
chosen) and the val split.

  python analysis/granularity.py [--model crack-detector-320.onnx]
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
from eval import coco_metrics, load_rgb, ort_outputs  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))
SETS = ("crackforest", "uav75", "quaywall")
FRACTIONS = {"none": None, "r/4": 0.005, "r/2": 0.01}
VARIANTS = {"shipped": [], "+ r/2": ["r/2"], "+ r/4": ["r/4"], "+ undilated": ["none"],
            "+ r/2, r/4, undilated": ["r/2", "r/4", "none"]}


def iou(a, b):
    iw = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    ih = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = iw * ih
    u = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / u if u > 0 else 0.0


def components(prob, w, h, size, fraction):
    """contract.map_to_detections with the dilation radius at `fraction` of max(W, H) (None: no dilation)."""
    saved = contract.DILATION_FRACTION, contract.dilation_radius_cells
    try:
        if fraction is None:
            contract.dilation_radius_cells = lambda *_: 0
        else:
            contract.DILATION_FRACTION = fraction
        return contract.map_to_detections(prob, w, h, size)
    finally:
        contract.DILATION_FRACTION, contract.dilation_radius_cells = saved


def detections(outputs, w, h, size, extra):
    out = contract.detections(outputs, w, h, size)
    prob = outputs["crack_map"][0, 0]
    for name in extra:
        for x0, y0, x1, y1, sc in components(prob, w, h, size, FRACTIONS[name]):
            box = (x0, y0, x1, y1)
            if all(iou(box, d[:4]) <= 0.9 for d in out):
                out.append((x0, y0, x1, y1, 0.01 * (sc - 0.5) / 0.5 * 0.999))
    return out[:contract.MAX_DETECTIONS]


def evaluate(run, size, split):
    rows = {}
    dets = {v: {ds: [] for ds in SETS} for v in VARIANTS}
    cocos = {}
    for ds in SETS:
        coco = json.load(open(os.path.join(DATA, ds, f"{split}.json")))
        cocos[ds] = coco
        for im in coco["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            h, w = img.shape[:2]
            x, _ = contract.letterbox(img, size)
            outputs = run(x)
            for v, extra in VARIANTS.items():
                for x0, y0, x1, y1, sc in detections(outputs, w, h, size, extra):
                    dets[v][ds].append({"image_id": im["id"], "category_id": 1,
                                        "bbox": [x0, y0, x1 - x0, y1 - y0], "score": sc})
    for v in VARIANTS:
        per = {}
        merged = {"images": [], "annotations": [], "categories": [{"id": 1, "name": "crack"}]}
        merged_dets = []
        offset = 0
        for ds in SETS:
            m = coco_metrics(cocos[ds], dets[v][ds])
            per[ds] = (m["mAP50"], m["AR100"])
            # Image ids repeat across sets: offset them for the merged evaluation.
            ids = {im["id"]: offset + k for k, im in enumerate(cocos[ds]["images"])}
            merged["images"] += [{**im, "id": ids[im["id"]]} for im in cocos[ds]["images"]]
            merged["annotations"] += [{**a, "id": len(merged["annotations"]) + k + 1,
                                       "image_id": ids[a["image_id"]]}
                                      for k, a in enumerate(cocos[ds]["annotations"])]
            merged_dets += [{**d, "image_id": ids[d["image_id"]]} for d in dets[v][ds]]
            offset += len(ids)
        m = coco_metrics(merged, merged_dets)
        per["merged"] = (m["mAP50"], m["AR100"])
        rows[v] = per
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    a = ap.parse_args()
    run, size = ort_outputs(a.model, threads=1)
    for split in ("train", "val"):
        rows = evaluate(run, size, split)
        print(f"== {split}: mAP@0.5 / AR@100 (%)")
        for v, per in rows.items():
            print(f"{v:24s} " + "  ".join(f"{k} {p[0] * 100:5.1f}/{p[1] * 100:5.1f}" for k, p in per.items()),
                  flush=True)


if __name__ == "__main__":
    main()
