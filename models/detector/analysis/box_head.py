"""Would a box head trained on the photos' own boxes beat the map -> boxes rule? A probe, not a shipped model.

The rule (contract.py) turns the crack map into one box per dilated component. AR@100 stays near 45 % on the val
photos whatever the rule's variant (MODEL_CARD.md, *The score*): quaywall's boxes are chains of small hand-drawn
boxes along one crack, which no component rule reproduces. This probe trains a CenterNet-style head (a heatmap of
box centres, their width and height and a sub-cell offset, at stride 8) on the **frozen** features of the committed
ONNX crack-map model, on the photos' train splits only (all three sets' COCO boxes), and compares it with the rule on
the val splits, by pycocotools, per set and merged.

The frozen features are read out of the ONNX graph itself (the decoder's stride-8 feature, the encoder's deepest
context feature, the crack map), so the probe needs no PyTorch checkpoint of the model. Features of every
augmented training image (8 flips/transposes x crops) are computed once with ONNX Runtime and cached in memory;
only the head is trained (one PyTorch thread, --minutes).

  python analysis/box_head.py --model crack-detector-320.onnx --minutes 25 [--crops 2] [--out /tmp/box_head]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np
import onnx
import torch
import torch.nn as nn
import torch.nn.functional as F
from onnx import shape_inference

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import coco_metrics, load_rgb  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))
SETS = ("crackforest", "uav75", "quaywall")
HEAD_STRIDE = contract.HEAD_STRIDE


# --------------------------------------------------------------------------------------------------------------
# Frozen features out of the ONNX graph
# --------------------------------------------------------------------------------------------------------------

def tapped_model(path: str, size: int):
    """The ONNX model with two more outputs: the last value of stride 8 and the last of the coarsest stride
    (by inferred shape, in graph order). Returns (model bytes, [names])."""
    m = onnx.load(path)
    inferred = shape_inference.infer_shapes(m)
    shapes = {}
    for vi in list(inferred.graph.value_info) + list(inferred.graph.output):
        dims = [d.dim_value for d in vi.type.tensor_type.shape.dim]
        shapes[vi.name] = dims
    by_stride = {}
    for node in m.graph.node:
        for o in node.output:
            d = shapes.get(o)
            if d and len(d) == 4 and d[2] > 0 and d[1] > 1:
                by_stride.setdefault(size // d[2], []).append((o, d))
    s8 = by_stride[HEAD_STRIDE][-1]
    deepest = by_stride[max(by_stride)][-1]
    for name, d in (s8, deepest):
        m.graph.output.append(onnx.helper.make_tensor_value_info(name, onnx.TensorProto.FLOAT, d))
    return m.SerializeToString(), [s8[0], deepest[0]], [s8[1][1], deepest[1][1]]


def session(model: bytes, threads: int):
    """An ONNX Runtime CPU session of a serialized model on `threads` intra-op threads."""
    import onnxruntime as ort
    so = ort.SessionOptions()
    so.intra_op_num_threads = threads
    return ort.InferenceSession(model, so, providers=["CPUExecutionProvider"])


class Features:
    def __init__(self, model: str, size: int, threads: int = 2):
        raw, self.names, self.channels = tapped_model(model, size)
        self.sess = session(raw, threads)
        self.size = size

    def __call__(self, img: np.ndarray):
        """RGB8 image -> (crack map [S/2,S/2], f8 [C,S/8,S/8], deep [C,S/k,S/k], letterbox scale)."""
        x, s = contract.letterbox(img, self.size)
        cmap, f8, deep = self.sess.run(["crack_map"] + self.names, {"images": x})
        return cmap[0, 0], f8[0], deep[0], s


def stack_inputs(cmap, f8, deep):
    """What the head sees at stride 8, batched tensors: the crack map [B, 1, S/2, S/2] max- and mean-pooled,
    f8 [B, C8, S/8, S/8], deep [B, Cd, S/32, S/32] upsampled. The one stacking, here and in the merged graph."""
    k = cmap.shape[-1] // f8.shape[-1]
    pooled = torch.cat([F.max_pool2d(cmap, k), F.avg_pool2d(cmap, k)], 1)
    up = F.interpolate(deep, size=f8.shape[-2:], mode="nearest")
    return torch.cat([pooled, f8, up], 1)


def head_input(cmap, f8, deep):
    """stack_inputs of one image's numpy outputs, unbatched (float16 to keep the cache small)."""
    t = torch.from_numpy
    return stack_inputs(t(cmap)[None, None], t(f8)[None], t(deep)[None])[0].half()


# --------------------------------------------------------------------------------------------------------------
# Data: the photos' COCO boxes, augmented by the 8 flips/transposes and random crops
# --------------------------------------------------------------------------------------------------------------

def load_split(split: str):
    out = []
    for ds in SETS:
        coco = json.load(open(os.path.join(DATA, ds, f"{split}.json")))
        boxes = {}
        for a in coco["annotations"]:
            x, y, w, h = a["bbox"]
            boxes.setdefault(a["image_id"], []).append([x, y, x + w, y + h])
        for im in coco["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            out.append((ds, im["id"], img, np.array(boxes.get(im["id"], []), np.float32).reshape(-1, 4)))
    return out


def dihedral(img, boxes, k):
    """k in 0..7: bit 0 flip x, bit 1 flip y, bit 2 transpose."""
    h, w = img.shape[:2]
    b = boxes.copy()
    if k & 1:
        img = img[:, ::-1]
        b[:, [0, 2]] = w - boxes[:, [2, 0]]
    if k & 2:
        img = img[::-1]
        b[:, [1, 3]] = h - b[:, [3, 1]]
    if k & 4:
        img = img.transpose(1, 0, 2)
        b = b[:, [1, 0, 3, 2]]
    return np.ascontiguousarray(img), b


def random_crop(img, boxes, rng, keep=0.5):
    """A crop of 60-100 % of each side; boxes clipped, those keeping under `keep` of their area dropped."""
    h, w = img.shape[:2]
    cw, ch = int(w * rng.uniform(0.6, 1.0)), int(h * rng.uniform(0.6, 1.0))
    x0, y0 = int(rng.integers(0, w - cw + 1)), int(rng.integers(0, h - ch + 1))
    b = boxes - np.array([x0, y0, x0, y0], np.float32)
    area = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    b[:, [0, 2]] = b[:, [0, 2]].clip(0, cw)
    b[:, [1, 3]] = b[:, [1, 3]].clip(0, ch)
    kept = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1]) >= keep * np.maximum(area, 1e-6)
    return np.ascontiguousarray(img[y0:y0 + ch, x0:x0 + cw]), b[kept]


def targets(boxes, s, n):
    """Boxes (image px) -> heat [n,n] (elliptical Gaussians at the centres, TTFNet-style), size [2,n,n] (log w, h in
    cells), offset [2,n,n], mask [n,n] of the centre cells."""
    heat = np.zeros((n, n), np.float32)
    size = np.zeros((2, n, n), np.float32)
    off = np.zeros((2, n, n), np.float32)
    mask = np.zeros((n, n), np.float32)
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float32)
    order = np.argsort(-(boxes[:, 2] - boxes[:, 0]) * (boxes[:, 3] - boxes[:, 1]))  # small boxes win their cells
    for x0, y0, x1, y1 in boxes[order] * s / HEAD_STRIDE:
        bw, bh = max(x1 - x0, 0.25), max(y1 - y0, 0.25)
        cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
        ix, iy = min(int(cx), n - 1), min(int(cy), n - 1)
        sx, sy = max(0.54 * bw / 6, 0.5), max(0.54 * bh / 6, 0.5)
        g = np.exp(-((xx - ix) ** 2) / (2 * sx * sx) - ((yy - iy) ** 2) / (2 * sy * sy))
        heat = np.maximum(heat, g)
        size[:, iy, ix] = (math.log(bw), math.log(bh))
        off[:, iy, ix] = (cx - ix, cy - iy)
        mask[iy, ix] = 1
    return heat, size, off, mask


def build_cache(feats: Features, items, rng, crops: int, augment: bool):
    xs, ys = [], []
    n = feats.size // HEAD_STRIDE
    for _, _, img, boxes in items:
        views = [(img, boxes)]
        if augment:
            views = []
            for k in range(8):
                im_k, b_k = dihedral(img, boxes, k)
                views.append((im_k, b_k))
                views += [random_crop(im_k, b_k, rng) for _ in range(crops)]
        for im_v, b_v in views:
            cmap, f8, deep, s = feats(im_v)
            xs.append(head_input(cmap, f8, deep))
            ys.append(tuple(torch.from_numpy(t) for t in targets(b_v, s, n)))
    return xs, ys


# --------------------------------------------------------------------------------------------------------------
# The head, its loss, its decoding
# --------------------------------------------------------------------------------------------------------------

def cbr(cin, cout, d=1):
    return nn.Sequential(nn.Conv2d(cin, cout, 3, 1, d, dilation=d, bias=False), nn.BatchNorm2d(cout),
                         nn.ReLU(inplace=True))


class BoxHead(nn.Module):
    def __init__(self, cin, c=64):
        super().__init__()
        self.body = nn.Sequential(nn.Conv2d(cin, c, 1, bias=False), nn.BatchNorm2d(c), nn.ReLU(inplace=True),
                                  cbr(c, c), cbr(c, c, 2), cbr(c, c, 4), cbr(c, c, 8))
        self.heat = nn.Conv2d(c, 1, 1)
        self.reg = nn.Conv2d(c, 4, 1)
        nn.init.constant_(self.heat.bias, -2.19)

    def forward(self, x):
        y = self.body(x)
        return self.heat(y), self.reg(y)


def focal(logit, heat, alpha=2.0, beta=4.0):
    p = torch.sigmoid(logit).clamp(1e-4, 1 - 1e-4)
    pos = heat >= 0.999
    pos_l = -((1 - p) ** alpha) * torch.log(p) * pos
    neg_l = -((1 - heat) ** beta) * (p ** alpha) * torch.log(1 - p) * (~pos)
    return (pos_l.sum() + neg_l.sum()) / pos.sum().clamp(min=1)


def loss_fn(head, x, heat, size, off, mask):
    hl, reg = head(x)
    l_heat = focal(hl[:, 0], heat)
    m = mask[:, None]
    n = mask.sum().clamp(min=1)
    l_size = (F.l1_loss(reg[:, :2], size, reduction="none") * m).sum() / n
    l_off = (F.l1_loss(reg[:, 2:], off, reduction="none") * m).sum() / n
    return l_heat + 0.5 * l_size + l_off


def decode(head, x, s, w, h, max_det=contract.MAX_DETECTIONS):
    with torch.no_grad():
        hl, reg = head(x[None].float())
    return decode_maps(torch.sigmoid(hl)[0, 0], reg, s, w, h, max_det)


def decode_maps(p, reg, s, w, h, max_det=contract.MAX_DETECTIONS):
    """Boxes (x0, y0, x1, y1, p) in image pixels from the head's centre probabilities p [n, n] and its regression
    reg [1, 4, n, n], by the contract's decoding (contract.head_to_detections), with the head's own probability as
    the score. s, the letterbox scale, is implied by w, h and the map's side."""
    size = p.shape[-1] * HEAD_STRIDE
    found = contract.head_to_detections(p.numpy(), reg.numpy(), w, h, size, max_det)
    return [(x0, y0, x1, y1, sc / contract.HEAD_SCORE_SCALE) for x0, y0, x1, y1, sc in found]


# --------------------------------------------------------------------------------------------------------------

def evaluate(head, feats, val, rule=True, boxes_of=None):
    """pycocotools mAP@0.5 / AR@100 per set and merged, for the head (and the rule on the same maps, and the
    rule's boxes followed by the head's). boxes_of(cmap, f8, deep, s, w, h) gives the head's boxes of one
    image; by default the torch head's."""
    if boxes_of is None:
        def boxes_of(cmap, f8, deep, s, w, h):
            return decode(head, head_input(cmap, f8, deep), s, w, h)
    head.eval()
    res = {"head": {}, "rule": {}, "union": {}}
    merged = {"images": [], "annotations": [], "categories": [{"id": 1, "name": "crack"}]}
    dets = {"head": [], "rule": [], "union": []}
    per = {ds: {"images": [], "annotations": [], "categories": merged["categories"]} for ds in SETS}
    per_dets = {k: {ds: [] for ds in SETS} for k in dets}
    aid = 1
    for ds, iid, img, boxes in val:
        h, w = img.shape[:2]
        cmap, f8, deep, s = feats(img)
        im = {"id": iid, "width": w, "height": h}
        for coco in (merged, per[ds]):
            coco["images"].append(im)
        for x0, y0, x1, y1 in boxes:
            a = {"id": aid, "image_id": iid, "category_id": 1, "bbox": [float(x0), float(y0), float(x1 - x0),
                                                                      float(y1 - y0)],
                 "area": float((x1 - x0) * (y1 - y0)), "iscrowd": 0}
            aid += 1
            merged["annotations"].append(a)
            per[ds]["annotations"].append(a)
        found = {"head": boxes_of(cmap, f8, deep, s, w, h)}
        if rule:
            found["rule"] = contract.map_to_detections(cmap, w, h, feats.size)
            # The rule's boxes first, then the head's below every one of them (rule scores are >= 0.5).
            found["union"] = found["rule"] + [(x0, y0, x1, y1, 0.5 * sc) for x0, y0, x1, y1, sc in found["head"]]
        for k, ds_dets in found.items():
            for x0, y0, x1, y1, sc in ds_dets:
                d = {"image_id": iid, "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0], "score": sc}
                dets[k].append(d)
                per_dets[k][ds].append(d)
    for k in dets:
        if not dets[k]:
            continue
        for ds in SETS:
            m = coco_metrics(per[ds], per_dets[k][ds])
            res[k][ds] = (m["mAP50"], m["AR100"], m["mAP"])
        m = coco_metrics(merged, dets[k])
        res[k]["merged"] = (m["mAP50"], m["AR100"], m["mAP"])
    head.train()
    return res


def fmt(res):
    lines = []
    for k, r in res.items():
        if r:
            lines.append(f"{k:5s} " + "  ".join(f"{ds} {v[0] * 100:5.1f}/{v[1] * 100:5.1f}/{v[2] * 100:5.1f}"
                                                for ds, v in r.items()))
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--size", type=int, default=320)
    ap.add_argument("--minutes", type=float, default=25.0)
    ap.add_argument("--crops", type=int, default=2, help="random crops per flip/transpose of each train image")
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--eval-every", type=float, default=5.0, help="minutes between val evaluations")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--channels", type=int, default=64, help="the head's width")
    ap.add_argument("--out", default=None, help="folder for the head's weights and the val figures (JSON)")
    ap.add_argument("--eval-only", default=None, help="a trained head's box_head.pt: evaluate it on val, no training")
    a = ap.parse_args()
    torch.set_num_threads(1)
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    feats = Features(a.model, a.size)
    if a.eval_only:
        head = BoxHead(sum(feats.channels) + 2, a.channels)
        head.load_state_dict(torch.load(a.eval_only))
        print(fmt(evaluate(head, feats, load_split("val"))), flush=True)
        return
    t0 = time.time()
    train = load_split("train")
    val = load_split("val")
    xs, ys = build_cache(feats, train, rng, a.crops, augment=True)
    print(f"cache: {len(xs)} views of {len(train)} train images in {time.time() - t0:.0f} s, "
          f"{xs[0].shape[0]} channels", flush=True)
    head = BoxHead(xs[0].shape[0], a.channels)
    opt = torch.optim.AdamW(head.parameters(), lr=a.lr, weight_decay=1e-4)
    budget = a.minutes * 60
    start = time.time()
    next_eval = a.eval_every * 60
    step, history = 0, []
    while time.time() - start < budget:
        frac = (time.time() - start) / budget
        for g in opt.param_groups:
            g["lr"] = a.lr * 0.5 * (1 + math.cos(math.pi * frac))
        idx = rng.integers(len(xs), size=a.batch)
        x = torch.stack([xs[i] for i in idx]).float()
        t = [torch.stack([ys[i][j] for i in idx]) for j in range(4)]
        loss = loss_fn(head, x, *t)
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        if step % 200 == 0:
            print(f"step {step} {time.time() - start:.0f} s loss {loss.item():.3f}", flush=True)
        if time.time() - start >= next_eval:
            next_eval += a.eval_every * 60
            r = evaluate(head, feats, val, rule=not history)
            history.append({"step": step, "seconds": time.time() - start, "val": r})
            print(f"== step {step}\n{fmt(r)}", flush=True)
    r = evaluate(head, feats, val)
    history.append({"step": step, "seconds": time.time() - start, "val": r})
    print(f"== final, step {step}\n{fmt(r)}", flush=True)
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        torch.save(head.state_dict(), os.path.join(a.out, "box_head.pt"))
        json.dump({"args": vars(a), "history": history}, open(os.path.join(a.out, "history.json"), "w"), indent=1)


if __name__ == "__main__":
    main()
