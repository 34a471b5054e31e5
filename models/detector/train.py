"""Train the crack-map model: real photos with masks (crackforest, uav75), quaywall's boxes (weak, box-level
supervision), the DeepCrack and CRACK500 tiles with masks (`../shared/data/cracks-tiles`) and the simulator's rendered
plates with exact masks (`crackbot-lab sim detector-set`). `--arch effseg --pretrained FILE` starts the encoder from
the ImageNet EfficientNet-Lite0 weights (see setup.sh); `--arch crackseg` is the earlier from-scratch network.

Wall-clock budgeted: cosine LR over --minutes. The EMA weights are checkpointed; model selection uses the real val
splits only (val_all mAP@0.5 through the box rule of contract.py), never the unseen rendered scenes.
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
from PIL import Image, ImageFilter

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from contract import letterbox, resize_bilinear  # noqa: E402
from model import OUTPUT_STRIDE, build  # noqa: E402
from contract import map_to_detections  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))
TILES = os.environ.get("CRACK_TILES_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks-tiles")))
TILE_SETS = ("deepcrack", "crack500")
REF_SIZE = 320  # the default input: training scales are jittered around its letterbox scale


def load_rgb(path):
    return np.asarray(Image.open(path).convert("RGB"))


class Source:
    """Images with either a dense mask (uint8 0/1, same size) or a list of boxes [x0,y0,x1,y1]."""

    def __init__(self, name, items, weight, native=False):
        # native: scale around the image's own resolution (tiles are crops at camera scale), not to fill REF_SIZE
        self.name, self.items, self.weight, self.native = name, items, weight, native


def real_sources(split="train"):
    out = []
    for ds in ("crackforest", "uav75"):
        d = json.load(open(os.path.join(DATA, ds, f"{split}.json")))
        items = []
        for im in d["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            m = (np.asarray(Image.open(os.path.join(DATA, ds, im["mask_file"])).convert("L")) > 0).astype(np.uint8)
            items.append((img, m, None))
        out.append(Source(ds, items, 1.0))
    d = json.load(open(os.path.join(DATA, "quaywall", f"{split}.json")))
    boxes = {}
    for a in d["annotations"]:
        x, y, w, h = a["bbox"]
        boxes.setdefault(a["image_id"], []).append([x, y, x + w, y + h])
    items = [(load_rgb(os.path.join(DATA, "quaywall", im["file_name"])), None,
              np.array(boxes.get(im["id"], []), dtype=np.float32).reshape(-1, 4)) for im in d["images"]]
    out.append(Source("quaywall", items, 1.0))
    return out


def tile_sources(split="train"):
    out = []
    for ds in TILE_SETS:
        root = os.path.join(TILES, ds)
        if not os.path.isdir(root):
            raise FileNotFoundError(f"crack tiles not found at {root} (set CRACK_TILES_DATA)")
        d = json.load(open(os.path.join(root, f"{split}.json")))
        items = []
        for im in d["images"]:
            img = load_rgb(os.path.join(root, im["file_name"]))
            m = (np.asarray(Image.open(os.path.join(root, im["mask_file"])).convert("L")) > 127).astype(np.uint8)
            items.append((img, m, None))
        out.append(Source(ds, items, 1.0, native=True))
    return out


def sim_source(root):
    ann = json.load(open(os.path.join(root, "annotations.json")))
    items = []
    for im in ann["images"]:
        img = load_rgb(os.path.join(root, "images", os.path.basename(im["file_name"])))
        m = (np.asarray(Image.open(os.path.join(root, im["mask_file"])).convert("L")) > 0).astype(np.uint8)
        items.append((img, m, None))
    return Source("sim", items, 1.0)


def mask_to_canvas(mask, nw, nh):
    """0/1 mask -> canvas-resolution 0/1 (a canvas pixel is crack if >= 25% of its area is)."""
    m = Image.fromarray(mask * 255).resize((nw, nh), Image.BOX)
    return (np.asarray(m) >= 64).astype(np.uint8)


def sample(src, rng, crop):
    """One augmented crop: (img float32 [crop,crop,3] 0..1, target u8 [c/2,c/2] (0/1/255=ignore),
    valid f32 [c/2,c/2], boxes in target cells (weak) or None)."""
    img, mask, boxes = src.items[rng.integers(len(src.items))]
    h, w = img.shape[:2]
    base = 1.0 if src.native else REF_SIZE / max(w, h)
    s = base * math.exp(rng.uniform(math.log(0.7), math.log(1.45)))
    nw, nh = max(1, int(w * s + 0.5)), max(1, int(h * s + 0.5))
    im = resize_bilinear(img, nw, nh) / 255.0
    if mask is not None:
        m = mask_to_canvas(mask, nw, nh)
    else:
        m = None
        bx = boxes * np.array([nw / w, nh / h, nw / w, nh / h], dtype=np.float32)
    # random crop / placement on a crop x crop canvas (pad 0.5), offsets even so cells align
    ox = int(rng.integers(0, max(nw - crop, 0) + 1)) // 2 * 2
    oy = int(rng.integers(0, max(nh - crop, 0) + 1)) // 2 * 2
    canvas = np.full((crop, crop, 3), 0.5, dtype=np.float32)
    cm = np.zeros((crop, crop), dtype=np.uint8)
    valid = np.zeros((crop, crop), dtype=np.float32)
    pw, ph = min(crop, nw - ox), min(crop, nh - oy)
    canvas[:ph, :pw] = im[oy:oy + ph, ox:ox + pw]
    valid[:ph, :pw] = 1
    if m is not None:
        cm[:ph, :pw] = m[oy:oy + ph, ox:ox + pw]
    else:
        bx = bx - np.array([ox, oy, ox, oy], dtype=np.float32)
        bx[:, [0, 2]] = bx[:, [0, 2]].clip(0, pw)
        bx[:, [1, 3]] = bx[:, [1, 3]].clip(0, ph)
        bx = bx[((bx[:, 2] - bx[:, 0]) >= 4) & ((bx[:, 3] - bx[:, 1]) >= 4)]
    # photometric
    if rng.random() < 0.2:
        canvas[:ph, :pw] = canvas[:ph, :pw].mean(2, keepdims=True)
    gain = rng.uniform(0.65, 1.35)
    contrast = rng.uniform(0.7, 1.3)
    mean = canvas[:ph, :pw].mean()
    canvas[:ph, :pw] = ((canvas[:ph, :pw] - mean) * contrast + mean) * gain
    canvas[:ph, :pw] *= rng.uniform(0.9, 1.1, size=3).astype(np.float32)
    canvas = np.clip(canvas, 0, 1)
    canvas[:ph, :pw] = np.clip(canvas[:ph, :pw], 1e-4, 1) ** rng.uniform(0.75, 1.35)
    if rng.random() < 0.25:
        pil = Image.fromarray((canvas * 255).astype(np.uint8)).filter(ImageFilter.GaussianBlur(rng.uniform(0.3, 1.0)))
        canvas = np.asarray(pil).astype(np.float32) / 255.0
    if rng.random() < 0.5:
        canvas = canvas + rng.normal(0, rng.uniform(0.0, 0.03), canvas.shape).astype(np.float32)
    canvas = np.clip(canvas, 0, 1).astype(np.float32)
    # geometric (flips / transpose keep the padding as it is: apply to everything alike)
    k = OUTPUT_STRIDE
    tgt = cm.reshape(crop // k, k, crop // k, k).max((1, 3))
    val = valid.reshape(crop // k, k, crop // k, k).max((1, 3))
    weak = None
    if m is None:
        weak = bx / k
    ops = (rng.random() < 0.5, rng.random() < 0.5, rng.random() < 0.5)
    canvas, tgt, val, weak = geometric(canvas, tgt, val, weak, ops, crop // k)
    return canvas, tgt, val, weak


def geometric(img, tgt, val, weak, ops, n):
    fx, fy, tr = ops
    if fx:
        img, tgt, val = img[:, ::-1], tgt[:, ::-1], val[:, ::-1]
        if weak is not None:
            weak = np.stack([n - weak[:, 2], weak[:, 1], n - weak[:, 0], weak[:, 3]], 1)
    if fy:
        img, tgt, val = img[::-1], tgt[::-1], val[::-1]
        if weak is not None:
            weak = np.stack([weak[:, 0], n - weak[:, 3], weak[:, 2], n - weak[:, 1]], 1)
    if tr:
        img, tgt, val = img.transpose(1, 0, 2), tgt.T, val.T
        if weak is not None:
            weak = weak[:, [1, 0, 3, 2]]
    return (np.ascontiguousarray(img), np.ascontiguousarray(tgt), np.ascontiguousarray(val),
            None if weak is None else weak.astype(np.float32))


MIX_SOURCES = ("crackforest", "uav75", "quaywall") + TILE_SETS + ("sim",)


def parse_mix(text, have_sim):
    """`name=share,…` → {name: share}, shares normalised to 1; exits naming the bad part."""
    mix = {}
    for part in text.split(","):
        name, _, share = part.partition("=")
        name = name.strip()
        if name not in MIX_SOURCES:
            sys.exit(f"--mix: unknown source {name!r} in {part!r} (known: {', '.join(MIX_SOURCES)})")
        try:
            v = float(share)
        except ValueError:
            sys.exit(f"--mix: {part!r} needs a number after '='")
        if not (np.isfinite(v) and v > 0):
            sys.exit(f"--mix: the share of {name} must be a positive finite number, got {share!r}")
        mix[name] = v
    if "sim" in mix and not have_sim:
        sys.exit("--mix: 'sim' needs --sim (a folder of `crackbot-lab sim detector-set`)")
    total = sum(mix.values())
    return {n: v / total for n, v in mix.items()}


class Stream(torch.utils.data.IterableDataset):
    def __init__(self, sim_root, batch, crop, seed, mix):
        self.sim_root, self.batch, self.crop, self.seed, self.mix = sim_root, batch, crop, seed, mix

    def __iter__(self):
        info = torch.utils.data.get_worker_info()
        wid = info.id if info else 0
        srcs = {s.name: s for s in real_sources("train")}
        if any(n in self.mix for n in TILE_SETS):
            srcs.update({s.name: s for s in tile_sources("train")})
        if self.sim_root:
            srcs["sim"] = sim_source(self.sim_root)
        names = [n for n in self.mix if n in srcs]
        p = np.array([self.mix[n] for n in names], dtype=np.float64)
        p /= p.sum()
        rng = np.random.default_rng([self.seed, wid])
        while True:
            xs, ts, vs, weaks = [], [], [], []
            for _ in range(self.batch):
                src = srcs[names[rng.choice(len(names), p=p)]]
                x, t, v, wk = sample(src, rng, self.crop)
                xs.append(x); ts.append(t); vs.append(v); weaks.append(wk)
            x = torch.from_numpy(np.stack(xs)).permute(0, 3, 1, 2).contiguous()
            yield x, torch.from_numpy(np.stack(ts)), torch.from_numpy(np.stack(vs)), weaks


def seg_loss(logits, tgt, valid, weaks):
    """Dense samples: BCE (ignoring a one-cell band around cracks) + soft Dice. Weak (box) samples: MIL on the
    top cells of each box, background BCE outside all boxes at reduced weight."""
    lg = logits[:, 0]
    B = lg.shape[0]
    dense = torch.tensor([w is None for w in weaks])
    t = tgt.float()
    near = F.max_pool2d(t[:, None], 3, 1, 1)[:, 0]
    w = valid * (1.0 - (near - t))  # ignore the band next to a crack (label imprecision)
    w = torch.where(t > 0, 3.0 * valid, w)
    bce = F.binary_cross_entropy_with_logits(lg, t, reduction="none")
    total = lg.sum() * 0
    if dense.any():
        d = dense
        lb = (bce[d] * w[d]).sum() / w[d].sum().clamp(min=1)
        p = torch.sigmoid(lg[d]) * valid[d]
        inter = (p * t[d]).sum((1, 2))
        dice = 1 - (2 * inter + 1) / (p.sum((1, 2)) + t[d].sum((1, 2)) + 1)
        total = total + lb + dice.mean()
    mil_terms, bg_terms = [], []
    for i in range(B):
        if weaks[i] is None:
            continue
        inside = torch.zeros_like(lg[i], dtype=torch.bool)
        for bx in weaks[i]:
            x0, y0 = int(math.floor(bx[0])), int(math.floor(bx[1]))
            x1, y1 = int(math.ceil(bx[2])), int(math.ceil(bx[3]))
            if x1 - x0 < 1 or y1 - y0 < 1:
                continue
            inside[y0:y1, x0:x1] = True
            cells = lg[i, y0:y1, x0:x1].reshape(-1)
            k = max(1, int(0.5 * math.hypot(x1 - x0, y1 - y0)))
            top = cells.topk(min(k, cells.numel())).values
            mil_terms.append(F.binary_cross_entropy_with_logits(top, torch.ones_like(top)).reshape(1))
        out = (~inside) & (valid[i] > 0)
        if out.any():
            bg_terms.append(0.3 * bce[i][out].mean().reshape(1))
    if mil_terms:
        total = total + torch.cat(mil_terms).mean()
    if bg_terms:
        total = total + torch.cat(bg_terms).mean()
    return total


class EMA:
    def __init__(self, model, decay=0.998, tau=200):
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


@torch.no_grad()
def val_metrics(model, size=REF_SIZE):
    """val_all mAP@0.5 (pycocotools) of the box rule at threshold 0.5, and pixel F1 at 0.5 on masked val."""
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval
    import contextlib
    import io
    was_training = model.training
    model.eval()
    gt = json.load(open(os.path.join(DATA, "val_all.json")))
    res = []
    for im in gt["images"]:
        img = load_rgb(os.path.join(DATA, im["file_name"]))
        x, _ = letterbox(img, size)
        prob = model(torch.from_numpy(x)).numpy()[0, 0]
        for x0, y0, x1, y1, sc in map_to_detections(prob, im["width"], im["height"], size, threshold=0.5):
            res.append({"image_id": im["id"], "category_id": 1, "bbox": [x0, y0, x1 - x0, y1 - y0], "score": sc})
    with contextlib.redirect_stdout(io.StringIO()):
        c = COCO()
        c.dataset = gt
        c.createIndex()
        if not res:
            return {"mAP50": 0.0, "mAP": 0.0, "AR100": 0.0}
        d = c.loadRes(res)
        e = COCOeval(c, d, "bbox")
        e.evaluate(); e.accumulate(); e.summarize()
    model.train(was_training)
    return {"mAP": float(e.stats[0]), "mAP50": float(e.stats[1]), "AR100": float(e.stats[8])}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--minutes", type=float, default=45.0)
    ap.add_argument("--batch", type=int, default=12)
    ap.add_argument("--crop", type=int, default=256)
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--sim", default=os.environ.get("SIM_TRAIN", ""), help="folder of `crackbot-lab sim detector-set`")
    ap.add_argument("--eval-every", type=float, default=420.0)
    ap.add_argument("--out", default=os.path.join(HERE, "runs", "seg"))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--max-iters", type=int, default=0)
    ap.add_argument("--init", default=None, help="start from these weights (a best.pt/last.pt), with a new schedule")
    ap.add_argument("--resume", action="store_true",
                    help="continue the run in --out from its state.pt (weights, EMA, optimiser, step, elapsed "
                         "time, best): the schedule goes on where it stopped; without state.pt, start afresh")
    ap.add_argument("--arch", default="crackseg", help="crackseg (from scratch, the shipped default) or effseg "
                    "(the pretrained EfficientNet-Lite0 encoder; train_effseg.sh)")
    ap.add_argument("--pretrained", default="", help="EfficientNet-Lite0 ImageNet weights (.pth) for effseg")
    ap.add_argument("--encoder-lr", type=float, default=0.5, help="encoder learning rate as a fraction of --lr")
    ap.add_argument("--tiles", action="store_true", help="add the DeepCrack/CRACK500 train tiles to the default mix "
                    "(with --mix, the tiles load where the mix names them)")
    ap.add_argument("--bf16", action="store_true", help="forward pass in bfloat16 (CPU autocast, channels-last): "
                    "a training step 2.1-2.5x faster for CrackSeg and HED on a CPU with AVX512-BF16; weights, loss and EMA "
                    "stay float32")
    ap.add_argument("--mix", default="", help="the sources' shares, e.g. sim=0.4,deepcrack=0.15,… (overrides the "
                    "default mix; names: crackforest, uav75, quaywall, deepcrack, crack500, sim)")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    os.makedirs(a.out, exist_ok=True)
    if a.mix:
        mix = parse_mix(a.mix, bool(a.sim))
    elif not a.tiles:
        mix = {"crackforest": 0.25, "uav75": 0.25, "quaywall": 0.2, "sim": 0.3}
    else:
        mix = {"crackforest": 0.13, "uav75": 0.13, "quaywall": 0.12, "deepcrack": 0.18, "crack500": 0.16,
               "sim": 0.28}
    model = build(a.arch)
    state_path = os.path.join(a.out, "state.pt")
    state = torch.load(state_path, map_location="cpu") if a.resume and os.path.exists(state_path) else None
    if state is not None:
        if state["arch"] != a.arch:
            sys.exit(f"--resume: {state_path} is a {state['arch']} run, not {a.arch}")
        model.load_state_dict(state["model"])
        print(f"resuming {state_path}: step {state['it']}, {state['t'] / 60:.1f} of {a.minutes:.0f} min",
              flush=True)
    elif a.init:
        model.load_state_dict(torch.load(a.init, map_location="cpu")["model"])
    elif a.pretrained:
        loaded, skipped = model.load_pretrained(a.pretrained)
        print(f"pretrained: {loaded} tensors from {a.pretrained} ({skipped} not used)", flush=True)
    nparams = sum(p.numel() for p in model.parameters())
    print(f"params: {nparams}", flush=True)
    fmt = torch.channels_last if a.bf16 else torch.contiguous_format
    model = model.to(memory_format=fmt)
    ema = EMA(model)
    enc = set(id(p) for p in getattr(model, "encoder_parameters", lambda: [])())
    groups = [{"params": [p for p in model.parameters() if id(p) in enc], "scale": a.encoder_lr},
              {"params": [p for p in model.parameters() if id(p) not in enc], "scale": 1.0}]
    groups = [g for g in groups if g["params"]]
    opt = torch.optim.AdamW(groups, lr=a.lr, weight_decay=1e-4)
    it, elapsed, best = 0, 0.0, {"mAP50": -1.0}
    if state is not None:
        ema.m.load_state_dict(state["ema"])
        ema.n = state["ema_n"]
        opt.load_state_dict(state["opt"])
        it, elapsed, best = state["it"], state["t"], state["best"]
    # A resumed run draws other samples than the steps it already made.
    ds = Stream(a.sim, a.batch, a.crop, a.seed + it, mix)
    dl = torch.utils.data.DataLoader(ds, batch_size=None, num_workers=a.workers, persistent_workers=a.workers > 0,
                                     prefetch_factor=4 if a.workers else None,
                                     collate_fn=lambda b: b)
    budget = a.minutes * 60
    t0 = time.time() - elapsed
    last_eval = time.time()
    log = open(os.path.join(a.out, "log.jsonl"), "a")
    for x, t, v, weaks in dl:
        el = time.time() - t0
        prog = min(1.0, el / budget)
        lr = a.lr * min(1.0, (it + 1) / 100) * (0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * prog)))
        for g in opt.param_groups:
            g["lr"] = lr * g["scale"]
        model.train()
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=a.bf16):
            lg = model.logits(x.contiguous(memory_format=fmt))
        loss = seg_loss(lg.float(), t, v, weaks)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 5.0)
        opt.step()
        ema.update(model)
        it += 1
        if it % 25 == 0:
            rec = {"it": it, "t": round(el, 1), "lr": round(lr, 6), "loss": round(loss.item(), 4)}
            print(json.dumps(rec), flush=True)
            log.write(json.dumps(rec) + "\n"); log.flush()
        done = el >= budget or (a.max_iters and it >= a.max_iters)
        if time.time() - last_eval >= a.eval_every or done:
            te = time.time()
            m = val_metrics(ema.m)
            last_eval = time.time()
            rec = {"it": it, "t": round(el, 1), "eval_s": round(last_eval - te, 1), "val_all": m}
            ck = {"model": ema.m.state_dict(), "arch": a.arch, "it": it, "t": el, "metrics": m, "params": nparams}
            if (m["mAP50"], m["AR100"]) > (best["mAP50"], best.get("AR100", -1)):
                best = dict(m, it=it, t=round(el, 1))
                torch.save(ck, os.path.join(a.out, "best.pt"))
            torch.save(ck, os.path.join(a.out, "last.pt"))
            state = {"model": model.state_dict(), "ema": ema.m.state_dict(), "ema_n": ema.n,
                     "opt": opt.state_dict(), "it": it, "t": el, "best": best, "arch": a.arch}
            torch.save(state, state_path + ".tmp")
            os.replace(state_path + ".tmp", state_path)
            rec["best"] = best
            print(json.dumps(rec), flush=True)
            log.write(json.dumps(rec) + "\n"); log.flush()
        if done:
            break
    summary = {"iterations": it, "wall_s": round(time.time() - t0, 1), "batch": a.batch, "crop": a.crop,
               "images_seen": it * a.batch, "best": best, "params": nparams, "minutes_budget": a.minutes,
               "lr": a.lr, "seed": a.seed, "mix": mix, "sim": a.sim, "threads": a.threads, "arch": a.arch,
               "pretrained": os.path.basename(a.pretrained) if a.pretrained else None, "encoder_lr": a.encoder_lr,
               "bf16": a.bf16}
    json.dump(summary, open(os.path.join(a.out, "summary.json"), "w"), indent=1)
    print("summary:", json.dumps(summary), flush=True)


if __name__ == "__main__":
    main()
