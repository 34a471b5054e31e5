"""A trainable CrackSeg checkpoint from a shipped ONNX crack-map model, to fine-tune it where its PyTorch
checkpoint is gone (train.py --init).

The export folds each BatchNorm into the convolution before it (W, b). Loaded back with BatchNorm as the identity
(running mean 0, variance 1 - eps, scale 1, shift b) the network gives the ONNX model's crack map, but a BatchNorm in
training mode would normalise by batch statistics that are nothing like those. So each BatchNorm is "unfolded":
the per-channel mean mu and variance var of its convolution's output over real letterboxed train photos become its
running statistics, its scale sqrt(var + eps) and its shift b + mu. In eval mode that is the same function exactly
((y - mu) / sqrt(var + eps) * sqrt(var + eps) + b + mu = y + b); in training mode, on batches like those photos,
nearly so. The script checks the rebuilt model against ONNX Runtime on a photo.

  python analysis/onnx_to_checkpoint.py --model crack-detector-320.onnx --out /tmp/crackseg-from-onnx.pt
"""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
import onnx
import torch
import torch.nn as nn
from onnx import numpy_helper

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import load_rgb, ort_runner  # noqa: E402
from model import build  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))


def convs_in_call_order(model: nn.Module, size: int):
    """The model's Conv2d modules in the order a forward pass calls them (the order of the ONNX graph's Conv nodes)."""
    order, hooks = [], []
    for m in model.modules():
        if isinstance(m, nn.Conv2d):
            hooks.append(m.register_forward_hook(lambda mod, _i, _o: order.append(mod)))
    with torch.no_grad():
        model(torch.zeros(1, 3, size, size))
    for h in hooks:
        h.remove()
    return order


def batchnorm_after(model: nn.Module):
    """Conv2d -> the BatchNorm2d right after it in the same nn.Sequential."""
    out = {}
    for m in model.modules():
        if isinstance(m, nn.Sequential):
            kids = list(m)
            for a, b in zip(kids, kids[1:]):
                if isinstance(a, nn.Conv2d) and isinstance(b, nn.BatchNorm2d):
                    out[a] = b
    return out


def onnx_convs(path: str):
    """(W, b) of the ONNX graph's Conv nodes, in graph order."""
    m = onnx.load(path)
    init = {t.name: numpy_helper.to_array(t) for t in m.graph.initializer}
    return [(init[n.input[1]], init[n.input[2]] if len(n.input) > 2 else None)
            for n in m.graph.node if n.op_type == "Conv"]


def calibration_batch(size: int, n: int, seed: int = 0):
    """n letterboxed train photos (the three sets in turn), [n, 3, S, S]."""
    rng = np.random.default_rng(seed)
    files = []
    for ds in ("crackforest", "uav75", "quaywall"):
        coco = json.load(open(os.path.join(DATA, ds, "train.json")))
        files += [os.path.join(DATA, ds, im["file_name"]) for im in coco["images"]]
    pick = rng.choice(len(files), size=min(n, len(files)), replace=False)
    return torch.from_numpy(np.concatenate([contract.letterbox(load_rgb(files[i]), size)[0] for i in pick]))


def rebuild(model_path: str, size: int, calib: int):
    model = build("crackseg").eval()
    order = convs_in_call_order(model, size)
    bns = batchnorm_after(model)
    weights = onnx_convs(model_path)[:len(order)]
    if len(weights) != len(order):
        sys.exit(f"{model_path}: {len(weights)} Conv nodes, CrackSeg has {len(order)}: not a CrackSeg export")
    biases = {}
    for conv, (w, b) in zip(order, weights):
        if tuple(conv.weight.shape) != w.shape:
            sys.exit(f"{model_path}: a Conv of shape {w.shape} where CrackSeg has {tuple(conv.weight.shape)}")
        conv.weight.data = torch.from_numpy(w.copy())
        b = torch.from_numpy(b.copy()) if b is not None else torch.zeros(w.shape[0])
        if conv in bns:
            bn = bns[conv]
            bn.running_mean.zero_()
            bn.running_var.fill_(1.0 - bn.eps)
            bn.weight.data.fill_(1.0)
            bn.bias.data = b.clone()
            biases[conv] = b
        else:
            conv.bias.data = b
    # Statistics of each convolution's output over real photos, with the network as exported.
    stats, hooks = {}, []
    for conv in biases:
        def hook(mod, _i, out):
            stats[mod] = (out.mean((0, 2, 3)), out.var((0, 2, 3), unbiased=False))
        hooks.append(conv.register_forward_hook(hook))
    with torch.no_grad():
        model(calibration_batch(size, calib))
    for h in hooks:
        h.remove()
    for conv, b in biases.items():
        mu, var = stats[conv]
        bn = bns[conv]
        bn.running_mean.copy_(mu)
        bn.running_var.copy_(var)
        bn.weight.data = torch.sqrt(var + bn.eps)
        bn.bias.data = b + mu
    return model


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--size", type=int, default=320)
    ap.add_argument("--calibration-images", type=int, default=48)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    torch.set_num_threads(1)
    model = rebuild(a.model, a.size, a.calibration_images)
    run, _ = ort_runner(a.model, threads=1)
    coco = json.load(open(os.path.join(DATA, "uav75", "val.json")))
    x, _ = contract.letterbox(load_rgb(os.path.join(DATA, "uav75", coco["images"][0]["file_name"])), a.size)
    with torch.no_grad():
        ours = model(torch.from_numpy(x)).numpy()
        model.train()
        train_mode = model(calibration_batch(a.size, 12, seed=1)).numpy()
        model.eval()
        eval_mode = model(calibration_batch(a.size, 12, seed=1)).numpy()
    worst = float(np.abs(ours - run(x)).max())
    drift = float(np.abs(train_mode - eval_mode).mean())
    print(f"rebuilt from {a.model}: largest difference from ONNX Runtime on a val photo {worst:.2e}; "
          f"mean |train-mode - eval-mode| crack map on 12 other photos {drift:.3f}")
    if worst > 1e-3:
        sys.exit("the rebuilt model does not reproduce the ONNX model")
    torch.save({"model": model.state_dict(), "arch": "crackseg", "from_onnx": os.path.basename(a.model)}, a.out)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
