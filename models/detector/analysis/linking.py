"""Does joining a crack's pieces help the photo boxes? Variants of the map -> boxes rule on cached crack maps.

The failure table of MODEL_CARD.md puts 11 of uav75's and quaywall's 78 val boxes as "split in pieces": the map
holds a hairline crack as fragments farther apart than the rule's dilation. Variants tried here, each against the
contract's rule on the same maps:
  * dilate xK        - the rule with a K-times larger dilation radius (the naive join; merges neighbours too);
  * hysteresis T     - components grown through cells with p >= T (T < 0.5) before the dilation, boxes from the
                       crack cells (p >= 0.5) as before: a gap the map bridges faintly joins, a gap of nothing not;
  * collinear K/A    - components whose nearest ends lie within K dilation radii and whose gap runs within A
                       degrees of both components' axes are joined (union-find), boxes as the union of theirs;
  (all but "contract" and "score mean/L" score a component by the highest probability of its cells, the
  contract's score before 2026-12-04; "contract" is today's, "score mean/0.5" mapped to [0.5, 1])
  * score max        - the previous contract: the cells' highest probability;
  * score mean       - the contract's boxes, scored by the mean probability of their crack cells, not the max;
  * score mean/L     - that mean times min(1, box diagonal / (L * max(W, H)))^0.5 (short components ranked lower).
Maps come from the ONNX model once and are cached (--cache). Prints mAP@0.5 / AR@100 per set and variant.

  python analysis/linking.py --model crack-detector-320.onnx --split val [--cache /tmp/maps-val.npz]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import coco_metrics, load_rgb, ort_runner  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))
SETS = ("crackforest", "uav75", "quaywall")


def maps_for(model: str, split: str, cache: str | None):
    if cache and os.path.exists(cache):
        z = np.load(cache, allow_pickle=True)
        return z["maps"].item(), int(z["size"])
    run, size = ort_runner(model)
    maps = {}
    for ds in SETS:
        coco = json.load(open(os.path.join(DATA, ds, f"{split}.json")))
        for im in coco["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            x, _ = contract.letterbox(img, size)
            maps[(ds, im["id"])] = run(x)[0, 0]
    if cache:
        np.savez_compressed(cache, maps=np.array(maps, dtype=object), size=size)
    return maps, size


def components(prob, w, h, size, grow_threshold=None, dilate_scale=1.0):
    """Labels of the dilated map and the crack-cell mask, as the contract computes them (optionally grown)."""
    s, nw, nh = contract.letterbox_params(w, h, size)
    vr, vc = contract.valid_cells(size, nw, nh)
    p = prob[:vr, :vc]
    b = p >= np.float32(contract.MAP_THRESHOLD)
    base = b
    if grow_threshold is not None:
        weak, _ = ndimage.label(p >= np.float32(grow_threshold), structure=np.ones((3, 3), dtype=bool))
        keep = np.unique(weak[b])
        base = np.isin(weak, keep[keep > 0])
    r = max(1, int(round(contract.dilation_radius_cells(w, h, s) * dilate_scale)))
    dil = ndimage.binary_dilation(base, structure=contract.disk(r)) if b.any() else b
    labels, n = ndimage.label(dil, structure=np.ones((3, 3), dtype=bool))
    return p, b, labels, n, s, r


def boxes_of(groups, p, b, labels, w, h, s, score="max", length=0.0):
    out = []
    min_area = contract.MIN_AREA_FRACTION * w * h
    for ks in groups:
        cells = b & np.isin(labels, ks)
        rows, cols = np.nonzero(cells)
        if len(rows) == 0:
            continue
        x0 = min(contract.STRIDE * cols.min() / s, w)
        y0 = min(contract.STRIDE * rows.min() / s, h)
        x1 = min(contract.STRIDE * (cols.max() + 1) / s, w)
        y1 = min(contract.STRIDE * (rows.max() + 1) / s, h)
        if (x1 - x0) * (y1 - y0) < min_area:
            continue
        sc = float(p[cells].max()) if score == "max" else float(p[cells].mean())
        if length > 0:
            sc *= min(1.0, float(np.hypot(x1 - x0, y1 - y0)) / (length * max(w, h))) ** 0.5
        out.append((float(x0), float(y0), float(x1), float(y1), sc))
    out.sort(key=lambda d: -d[4])
    return out[:contract.MAX_DETECTIONS]


def axis_and_ends(rows, cols):
    pts = np.stack([cols, rows], 1).astype(np.float64)
    c = pts.mean(0)
    if len(pts) < 3:
        return c, np.array([1.0, 0.0]), 0.0, pts[0], pts[-1]
    cov = np.cov((pts - c).T)
    ev, evec = np.linalg.eigh(cov)
    u = evec[:, 1]
    elong = 1.0 - (ev[0] / ev[1] if ev[1] > 0 else 1.0)
    t = (pts - c) @ u
    return c, u, elong, pts[np.argmin(t)], pts[np.argmax(t)]


def collinear_groups(b, labels, n, r, reach, max_deg, min_elong=0.8):
    info = []
    for k in range(1, n + 1):
        rows, cols = np.nonzero(b & (labels == k))
        info.append(axis_and_ends(rows, cols) if len(rows) else None)
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    cos_max = np.cos(np.radians(max_deg))
    for i in range(n):
        for j in range(i + 1, n):
            a, c = info[i], info[j]
            if a is None or c is None or a[2] < min_elong or c[2] < min_elong:
                continue
            ends = [(np.linalg.norm(ea - ec), ea, ec) for ea in a[3:] for ec in c[3:]]
            d, ea, ec = min(ends, key=lambda e: e[0])
            if d > reach * r or d == 0:
                continue
            g = (ec - ea) / d
            if abs(g @ a[1]) >= cos_max and abs(g @ c[1]) >= cos_max:
                parent[find(i)] = find(j)
    groups = {}
    for k in range(n):
        groups.setdefault(find(k), []).append(k + 1)
    return list(groups.values())


def variant_dets(name, prob, w, h, size):
    if name.startswith("dilate"):
        p, b, labels, n, s, _ = components(prob, w, h, size, dilate_scale=float(name.split("x")[1]))
        return boxes_of([[k] for k in range(1, n + 1)], p, b, labels, w, h, s)
    if name.startswith("hysteresis"):
        p, b, labels, n, s, _ = components(prob, w, h, size, grow_threshold=float(name.split()[1]))
        return boxes_of([[k] for k in range(1, n + 1)], p, b, labels, w, h, s)
    if name.startswith("collinear"):
        reach, deg = (float(v) for v in name.split()[1].split("/"))
        p, b, labels, n, s, r = components(prob, w, h, size)
        groups = collinear_groups(b, labels, n, r, reach, deg)
        if name.endswith("score mean/0.5"):
            return boxes_of(groups, p, b, labels, w, h, s, score="mean", length=0.5)
        return boxes_of(groups, p, b, labels, w, h, s)
    if name.startswith("score"):
        arg = name.split()[1]
        p, b, labels, n, s, _ = components(prob, w, h, size)
        length = float(arg.split("/")[1]) if "/" in arg else 0.0
        kind = "max" if arg == "max" else "mean"
        return boxes_of([[k] for k in range(1, n + 1)], p, b, labels, w, h, s, score=kind, length=length)
    return contract.map_to_detections(prob, w, h, size)


VARIANTS = ("contract", "score max", "dilate x1.5", "dilate x2", "hysteresis 0.3", "hysteresis 0.15",
            "collinear 3/20", "collinear 5/20", "collinear 5/30",
            "collinear 8/30", "score mean", "score mean/0.3", "score mean/0.5",
            "collinear 8/30 + score mean/0.5")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--split", default="val")
    ap.add_argument("--cache", default=None)
    ap.add_argument("--variants", nargs="*", default=list(VARIANTS))
    a = ap.parse_args()
    maps, size = maps_for(a.model, a.split, a.cache)
    merged = json.load(open(os.path.join(DATA, f"{a.split}_all.json")))
    for v in a.variants:
        res = {ds: [] for ds in SETS}
        for ds in SETS:
            coco = json.load(open(os.path.join(DATA, ds, f"{a.split}.json")))
            for im in coco["images"]:
                for x0, y0, x1, y1, sc in variant_dets(v, maps[(ds, im["id"])], im["width"], im["height"], size):
                    res[ds].append({"image_id": im["id"], "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0],
                                    "score": sc})
        row = [f"{a.split} {v:16s}"]
        for ds in SETS:
            m = coco_metrics(json.load(open(os.path.join(DATA, ds, f"{a.split}.json"))), res[ds])
            row.append(f"{ds} {100 * m['mAP50']:5.1f}/{100 * m['AR100']:5.1f} ({m['detections']})")
        allres = [r for ds in SETS for r in res[ds]]
        m = coco_metrics(merged, allres)
        row.append(f"all {100 * m['mAP50']:5.1f}/{100 * m['AR100']:5.1f}")
        print("  ".join(row), flush=True)


if __name__ == "__main__":
    main()
