"""Deterministic paper-style augmented test set built ONLY from one split's images (default: val).

  python augmented_set.py --split val --out DIR --seed N [--count 200] [--size 320]

Writes DIR/images/aug_XXXX.png (SxS) and DIR/annotations.json (COCO, file_name relative to DIR, category crack=1).
Crack patches (crops around GT boxes) and crack-free patches of the split's photos are pasted into backgrounds
(crack-free regions of the same photos, or procedural concrete textures), 1-2 screws are drawn, and HSV jitter,
flip, scale, translate, rotate and shear are applied; 35% of the samples are the split's own images, jittered.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from augment import Augmenter, load_photos  # noqa: E402

# The crack photos beside the clone (../shared/data/cracks from the repository root); CRACKS_DATA overrides.
DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/data/cracks")))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--split", default="val", choices=["val", "train"])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--count", type=int, default=200)
    ap.add_argument("--size", type=int, default=320)
    a = ap.parse_args()
    photos = load_photos(os.path.join(DATA, f"{a.split}_all.json"), DATA)
    aug = Augmenter(photos, a.size)
    rng = np.random.default_rng([a.seed, 20251122])
    os.makedirs(os.path.join(a.out, "images"), exist_ok=True)
    images, anns = [], []
    i = 0
    while len(images) < a.count:
        canvas, boxes = aug.sample(rng)
        if len(boxes) == 0:  # keep every test image positive, like the source data
            continue
        i += 1
        name = f"images/aug_{i:04d}.png"
        Image.fromarray(canvas).save(os.path.join(a.out, name))
        images.append({"id": i, "file_name": name, "width": a.size, "height": a.size})
        for b in boxes:
            x0, y0, x1, y1 = [round(float(v), 2) for v in b]
            anns.append({"id": len(anns) + 1, "image_id": i, "category_id": 1, "bbox": [x0, y0, round(x1 - x0, 2), round(y1 - y0, 2)],
                         "area": round((x1 - x0) * (y1 - y0), 2), "iscrowd": 0})
    coco = {"info": {"description": f"paper-style augmented crack test set from the {a.split} split",
                     "seed": a.seed, "count": a.count, "size": a.size},
            "licenses": [], "images": images, "annotations": anns,
            "categories": [{"id": 1, "name": "crack", "supercategory": "crack"}]}
    with open(os.path.join(a.out, "annotations.json"), "w") as f:
        json.dump(coco, f)
    print(f"wrote {len(images)} images, {len(anns)} boxes to {a.out}")


if __name__ == "__main__":
    main()
