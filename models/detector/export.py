"""Export a trained crack-map checkpoint (EffSeg or CrackSeg) to fixed-size ONNX files (one per input size) and check them with onnxruntime."""
from __future__ import annotations

import argparse
import os
import sys
import warnings

import numpy as np
import torch

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from model import OUTPUT_STRIDE, build  # noqa: E402


def export(ckpt: str, sizes, out_dir: str):
    ck = torch.load(ckpt, map_location="cpu")
    model = build(ck.get("arch", "crackseg")).eval()
    model.load_state_dict(ck["model"])
    import onnx
    import onnxruntime as ort
    paths = []
    for s in sizes:
        assert s % 32 == 0, "input sizes must be multiples of 32"
        path = os.path.join(out_dir, f"crack-detector-{s}.onnx")
        x = torch.rand(1, 3, s, s)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            torch.onnx.export(model, (x,), path, input_names=["images"], output_names=["crack_map"],
                              opset_version=17, dynamo=False, do_constant_folding=True)
        m = onnx.load(path)
        onnx.checker.check_model(m)
        c = s // OUTPUT_STRIDE
        m.doc_string = (f"crackbot crack detector (crack map), input images [1,3,{s},{s}] RGB 0..1, "
                        f"output crack_map [1,1,{c},{c}] probabilities")
        onnx.save(m, path)
        sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
        o = sess.run(["crack_map"], {"images": x.numpy()})[0]
        with torch.no_grad():
            t = model(x).numpy()
        assert o.shape == (1, 1, c, c), o.shape
        print(f"{path}: output {o.shape}, max |ort - torch| = {np.abs(o - t).max():.2e}, "
              f"{os.path.getsize(path) / 1e6:.2f} MB")
        paths.append(path)
    return paths


if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("--ckpt", default=os.path.join(HERE, "runs", "eff", "best.pt"))
    ap.add_argument("--sizes", type=int, nargs="+", default=[320, 256, 416])
    ap.add_argument("--out", default=HERE)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    export(a.ckpt, a.sizes, a.out)
