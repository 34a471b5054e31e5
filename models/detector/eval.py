"""Evaluate a crack-detector ONNX model (onnxruntime + contract.py + pycocotools) on a COCO file.

  python eval.py --model crack-detector-320.onnx --ann ../shared/data/cracks/val_all.json \
      --root ../shared/data/cracks [--results out/dets.json] [--json-metrics out/m.json]

Boxes come from the crack map by the dataset rule (contract.map_to_detections), then, for a model with a box head,
the head's boxes below them (contract.detections). The project's own evaluator is
`crackbot eval-detector` (Rust); this script is its independent cross-check and what train.sh records.
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import contract  # noqa: E402


def load_rgb(path: str) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def detect_all(run_fn, coco: dict, root: str, size: int):
    """run_fn: float32 [1,3,S,S] -> the model's outputs by name (ort_outputs). Returns a COCO results list."""
    results = []
    for im in coco["images"]:
        img = load_rgb(os.path.join(root, im["file_name"]))
        h, w = img.shape[:2]
        x, _ = contract.letterbox(img, size)
        for x0, y0, x1, y1, sc in contract.detections(run_fn(x), w, h, size):
            results.append({"image_id": im["id"], "category_id": 1,
                            "bbox": [x0, y0, x1 - x0, y1 - y0], "score": sc})
    return results


def coco_metrics(coco: dict, results: list, verbose: bool = False) -> dict:
    from pycocotools.coco import COCO
    from pycocotools.cocoeval import COCOeval
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        gt = COCO()
        gt.dataset = coco
        gt.createIndex()
        if results:
            dt = gt.loadRes(results)
            ev = COCOeval(gt, dt, "bbox")
            ev.evaluate()
            ev.accumulate()
            ev.summarize()
            stats = [float(v) for v in ev.stats]
        else:
            stats = [0.0] * 12
    if verbose:
        print(buf.getvalue())
    return {"mAP": stats[0], "mAP50": stats[1], "mAP75": stats[2], "AR100": stats[8], "stats": stats,
            "images": len(coco["images"]), "boxes": len(coco["annotations"]), "detections": len(results)}


def ort_session(model_path: str, threads: int = 2):
    import onnxruntime as ort
    so = ort.SessionOptions()
    so.intra_op_num_threads = threads
    sess = ort.InferenceSession(model_path, so, providers=["CPUExecutionProvider"])
    return sess, sess.get_inputs()[0].shape[2]


def ort_runner(model_path: str, threads: int = 2):
    """(x -> the crack map [1,1,S/2,S/2], S)."""
    sess, size = ort_session(model_path, threads)
    return (lambda x: sess.run(["crack_map"], {"images": x})[0]), size


def ort_outputs(model_path: str, threads: int = 2):
    """(x -> every output of the model by name: crack_map, and box_heat and box_reg where it has a box head, S)."""
    sess, size = ort_session(model_path, threads)
    names = [o.name for o in sess.get_outputs()]
    return (lambda x: dict(zip(names, sess.run(names, {"images": x})))), size


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", required=True)
    ap.add_argument("--ann", required=True, help="COCO json")
    ap.add_argument("--root", default=None, help="image root (default: the json's folder)")
    ap.add_argument("--results", default=None, help="write COCO results JSON here")
    ap.add_argument("--json-metrics", default=None)
    ap.add_argument("--verbose", action="store_true")
    a = ap.parse_args()
    root = a.root or os.path.dirname(os.path.abspath(a.ann))
    with open(a.ann) as f:
        coco = json.load(f)
    run, size = ort_outputs(a.model)
    res = detect_all(run, coco, root, size)
    if a.results:
        os.makedirs(os.path.dirname(os.path.abspath(a.results)), exist_ok=True)
        with open(a.results, "w") as f:
            json.dump(res, f)
    m = coco_metrics(coco, res, a.verbose)
    print(f"{os.path.basename(a.model)} on {a.ann} (S={size}, {m['images']} images, {m['boxes']} boxes): "
          f"mAP@[.5:.95]={m['mAP']:.4f} mAP@0.5={m['mAP50']:.4f} AR@100={m['AR100']:.4f}")
    if a.json_metrics:
        with open(a.json_metrics, "w") as f:
            json.dump(m, f, indent=1)


if __name__ == "__main__":
    main()
