"""Train the crack detector from scratch on the three train splits (augmented on the fly).

Wall-clock-budgeted: the LR follows a cosine over --minutes; val_all mAP@[.5:.95] (pycocotools, through the
contract pipeline) picks the best EMA checkpoint.
"""
from __future__ import annotations

import argparse
import copy
import json
import math
import os
import sys
import time

import numpy as np
import torch
import torch.nn.functional as F

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from augment import Augmenter, load_photos  # noqa: E402
from model import STRIDES, CrackDet  # noqa: E402
import eval as ev  # noqa: E402

# The crack photos beside the clone (../shared/data/cracks from the repository root); CRACKS_DATA overrides.
DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../shared/data/cracks")))
RANGES = {16: (0, 192), 32: (64, 1e9)}  # max box side (canvas px) handled by each stride
RADIUS = 2.5


class AugStream(torch.utils.data.IterableDataset):
    def __init__(self, ann, root, size, batch, seed):
        self.ann, self.root, self.size, self.batch, self.seed = ann, root, size, batch, seed

    def __iter__(self):
        info = torch.utils.data.get_worker_info()
        wid = info.id if info else 0
        aug = Augmenter(load_photos(self.ann, self.root), self.size)
        rng = np.random.default_rng([self.seed, wid])
        while True:
            imgs, boxes = [], []
            for _ in range(self.batch):
                c, b = aug.sample(rng)
                imgs.append(c)
                boxes.append(b)
            x = torch.from_numpy(np.stack(imgs)).permute(0, 3, 1, 2).contiguous()  # uint8
            yield x, [torch.from_numpy(b) for b in boxes]


def giou(a, b):
    ix0 = torch.max(a[:, 0], b[:, 0]); iy0 = torch.max(a[:, 1], b[:, 1])
    ix1 = torch.min(a[:, 2], b[:, 2]); iy1 = torch.min(a[:, 3], b[:, 3])
    inter = (ix1 - ix0).clamp(min=0) * (iy1 - iy0).clamp(min=0)
    aa = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    bb = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    union = aa + bb - inter + 1e-7
    iou = inter / union
    cx0 = torch.min(a[:, 0], b[:, 0]); cy0 = torch.min(a[:, 1], b[:, 1])
    cx1 = torch.max(a[:, 2], b[:, 2]); cy1 = torch.max(a[:, 3], b[:, 3])
    carea = (cx1 - cx0) * (cy1 - cy0) + 1e-7
    return iou, iou - (carea - union) / carea


def assign(centres, stride, gt):
    """centres [M,2], gt [K,4] -> index of assigned gt per cell (-1 = negative)."""
    M = centres.shape[0]
    if gt.shape[0] == 0:
        return torch.full((M,), -1, dtype=torch.long)
    cx, cy = centres[:, 0:1], centres[:, 1:2]
    gw, gh = gt[:, 2] - gt[:, 0], gt[:, 3] - gt[:, 1]
    gcx, gcy = (gt[:, 0] + gt[:, 2]) / 2, (gt[:, 1] + gt[:, 3]) / 2
    inside = (cx > gt[:, 0]) & (cx < gt[:, 2]) & (cy > gt[:, 1]) & (cy < gt[:, 3])
    near = ((cx - gcx).abs() < RADIUS * stride) & ((cy - gcy).abs() < RADIUS * stride)
    lo, hi = RANGES[stride]
    m = torch.max(gw, gh)
    in_range = (m >= lo) & (m <= hi)
    cand = inside & near & in_range[None]
    # always keep the cell that contains the box centre (thin boxes may contain no cell centre)
    idx = ((gcy // stride).clamp(min=0) * 0).long()  # placeholder for shape
    cand_centre = ((cx - gcx).abs() <= stride / 2) & ((cy - gcy).abs() <= stride / 2) & in_range[None]
    cand = cand | cand_centre
    area = (gw * gh)[None].expand(M, -1).clone()
    area[~cand] = float("inf")
    best_area, best = area.min(1)
    best[torch.isinf(best_area)] = -1
    del idx
    return best


def compute_loss(model, x, gts):
    levels = model.decoded(x)
    B = x.shape[0]
    logits_all, tgt_all = [], []
    pbox_list, gbox_list = [], []
    for (logit, ltrb, c), stride in zip(levels, STRIDES):
        boxes = torch.cat([c[None] - ltrb[..., :2], c[None] + ltrb[..., 2:]], -1)  # [B,M,4]
        tgt = torch.zeros_like(logit)
        for i in range(B):
            a = assign(c, stride, gts[i])
            pos = a >= 0
            if pos.any():
                pb = boxes[i][pos]
                gb = gts[i][a[pos]]
                iou, _ = giou(pb.detach(), gb)
                tgt[i, pos] = iou.clamp(min=0.0).detach()
                pbox_list.append(pb)
                gbox_list.append(gb)
        logits_all.append(logit.reshape(-1))
        tgt_all.append(tgt.reshape(-1))
    logits = torch.cat(logits_all)
    tgt = torch.cat(tgt_all)
    npos = max(1, sum(p.shape[0] for p in pbox_list))
    # quality focal loss: BCE against the IoU target, modulated by |sigma - target|^2
    p = torch.sigmoid(logits)
    qfl = (F.binary_cross_entropy_with_logits(logits, tgt, reduction="none") * (p - tgt).abs().pow(2)).sum() / npos
    if pbox_list:
        _, g = giou(torch.cat(pbox_list), torch.cat(gbox_list))
        lbox = (1 - g).mean()
    else:
        lbox = logits.sum() * 0
    return qfl + 2.0 * lbox, qfl.item(), lbox.item(), npos


@torch.no_grad()
def evaluate_torch(model, coco, root, size):
    model.eval()
    run = lambda xx: model(torch.from_numpy(xx)).numpy()  # noqa: E731
    res = ev.detect_all(run, coco, root, size)
    return ev.coco_metrics(coco, res)


class EMA:
    def __init__(self, model, decay=0.998, tau=300):
        self.m = copy.deepcopy(model).eval()
        for p in self.m.parameters():
            p.requires_grad_(False)
        self.decay, self.tau, self.n = decay, tau, 0

    @torch.no_grad()
    def update(self, model):
        self.n += 1
        d = self.decay * (1 - math.exp(-self.n / self.tau))
        msd = model.state_dict()
        for k, v in self.m.state_dict().items():
            if v.dtype.is_floating_point:
                v.mul_(d).add_(msd[k].detach(), alpha=1 - d)
            else:
                v.copy_(msd[k])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--minutes", type=float, default=38.0, help="wall-clock training budget")
    ap.add_argument("--max-iters", type=int, default=0, help="optional iteration cap (0 = time only)")
    ap.add_argument("--batch", type=int, default=16)
    ap.add_argument("--size", type=int, default=320)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--eval-every", type=float, default=150.0, help="seconds between val evaluations")
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "runs", "train"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--init", default=None,
                    help="start from this checkpoint's weights (a second stage: a warm restart of the cosine)")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(DATA, "val_all.json")) as f:
        val = json.load(f)

    model = CrackDet()
    if a.init:
        model.load_state_dict(torch.load(a.init, map_location="cpu")["model"])
        print(f"initialised from {a.init}", flush=True)
    nparams = sum(p.numel() for p in model.parameters())
    print(f"params: {nparams}", flush=True)
    ema = EMA(model)
    decay, no_decay = [], []
    for n_, p in model.named_parameters():
        (no_decay if p.ndim <= 1 else decay).append(p)
    opt = torch.optim.AdamW([{"params": decay, "weight_decay": 5e-4}, {"params": no_decay, "weight_decay": 0}],
                            lr=a.lr, betas=(0.9, 0.99))
    ds = AugStream(os.path.join(DATA, "train_all.json"), DATA, a.size, a.batch, a.seed)
    dl = torch.utils.data.DataLoader(ds, batch_size=None, num_workers=a.workers,
                                     persistent_workers=a.workers > 0, prefetch_factor=4 if a.workers else None)
    budget = a.minutes * 60
    t0 = time.time()
    last_eval = t0
    best = {"mAP": -1}
    log = open(os.path.join(a.out, "log.jsonl"), "a")
    it = 0
    warm = 50 if a.init else 150
    for x, gts in dl:
        el = time.time() - t0
        prog = min(1.0, el / budget)
        lr = a.lr * min(1.0, (it + 1) / warm) * (0.05 + 0.95 * 0.5 * (1 + math.cos(math.pi * prog)))
        for g in opt.param_groups:
            g["lr"] = lr
        model.train()
        x = x.float() / 255.0
        gts = [g.float() for g in gts]
        loss, lq, lb, npos = compute_loss(model, x, gts)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
        opt.step()
        ema.update(model)
        it += 1
        if it % 20 == 0:
            rec = {"it": it, "t": round(el, 1), "lr": lr, "loss": loss.item(), "qfl": lq, "giou": lb, "npos": npos}
            print(json.dumps(rec), flush=True)
            log.write(json.dumps(rec) + "\n"); log.flush()
        done = el >= budget or (a.max_iters and it >= a.max_iters)
        if time.time() - last_eval >= a.eval_every or done:
            te = time.time()
            m = evaluate_torch(ema.m, val, DATA, a.size)
            last_eval = time.time()
            rec = {"it": it, "t": round(el, 1), "eval_s": round(last_eval - te, 1), "val_all": {k: m[k] for k in ("mAP", "mAP50", "AR100")}}
            improved = (m["mAP"], m["mAP50"]) > (best.get("mAP", -1), best.get("mAP50", -1))
            if improved:
                best = {"mAP": m["mAP"], "mAP50": m["mAP50"], "AR100": m["AR100"], "it": it, "t": round(el, 1)}
                torch.save({"model": ema.m.state_dict(), "it": it, "t": el, "metrics": m, "params": nparams},
                           os.path.join(a.out, "best.pt"))
            torch.save({"model": ema.m.state_dict(), "it": it, "t": el, "metrics": m, "params": nparams},
                       os.path.join(a.out, "last.pt"))
            rec["best"] = best
            print(json.dumps(rec), flush=True)
            log.write(json.dumps(rec) + "\n"); log.flush()
        if done:
            break
    summary = {"iterations": it, "wall_s": round(time.time() - t0, 1), "batch": a.batch, "size": a.size,
               "images_seen": it * a.batch, "best": best, "params": nparams, "minutes_budget": a.minutes,
               "lr": a.lr, "seed": a.seed, "init": a.init}
    with open(os.path.join(a.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print("summary:", json.dumps(summary), flush=True)


if __name__ == "__main__":
    main()
