"""Reference outputs for the Rust side: 3 val images (one per dataset) as PNG, their letterboxed input checksums,
crack maps, box-head outputs (models that have them) and detections from the 320 model via onnxruntime +
contract.py, and a synthetic-input check per size."""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import ort_outputs, ort_runner  # noqa: E402

# The crack photos beside the clone (../shared/data/cracks from the repository root); CRACKS_DATA overrides.
DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))
DATASETS = ["crackforest", "uav75", "quaywall"]


def synthetic_input(size: int) -> np.ndarray:
    c = np.arange(3)[:, None, None]
    y = np.arange(size)[None, :, None]
    x = np.arange(size)[None, None, :]
    return (((c * 7 + y * 3 + x * 5) % 17) / 16.0).astype(np.float32)[None]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--models", default=HERE)
    ap.add_argument("--out", default=os.path.join(HERE, "reference"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    run320, size = ort_outputs(os.path.join(a.models, "crack-detector-320.onnx"), threads=1)
    assert size == 320
    ref = {"contract": {"S": 320, "pad": 0.5, "map_threshold": contract.MAP_THRESHOLD,
                        "max_det": contract.MAX_DETECTIONS,
                        "note": "crack maps and detections computed with onnxruntime on the PNG via contract.py"},
           "images": [], "synthetic": []}
    for ds in DATASETS:
        with open(os.path.join(DATA, ds, "val.json")) as f:
            coco = json.load(f)
        im = sorted(coco["images"], key=lambda r: r["id"])[0]
        img = np.asarray(Image.open(os.path.join(DATA, ds, im["file_name"])).convert("RGB"))
        png = f"ref_{ds}.png"
        Image.fromarray(img).save(os.path.join(a.out, png))
        img = np.asarray(Image.open(os.path.join(a.out, png)).convert("RGB"))  # round-trip (lossless)
        h, w = img.shape[:2]
        x, s = contract.letterbox(img, 320)
        outputs = run320(x)
        prob = outputs["crack_map"][0, 0]
        dets = contract.detections(outputs, w, h, 320)
        head = {}
        if "box_heat" in outputs:
            head = {"box_heat_sum": float(outputs["box_heat"].astype(np.float64).sum()),
                    "box_reg_sum": float(outputs["box_reg"].astype(np.float64).sum()),
                    "box_head_detections": len(contract.head_to_detections(outputs["box_heat"], outputs["box_reg"],
                                                                           w, h, 320))}
        gts = [a_["bbox"] for a_ in coco["annotations"] if a_["image_id"] == im["id"]]
        ref["images"].append({
            "file": png, "dataset": ds, "source_file": f"{ds}/{im['file_name']}", "W": w, "H": h, "S": 320,
            "scale": s, "input_checksum": {"sum": float(x.astype(np.float64).sum()),
                                           "first8_row0_R": [float(v) for v in x[0, 0, 0, :8]]},
            "map_sum": float(prob.astype(np.float64).sum()),
            "map_cells_at_least_threshold": int((prob >= contract.MAP_THRESHOLD).sum()),
            **head,
            "detections": [{"bbox": [d[0], d[1], d[2], d[3]], "score": d[4],
                            "source": "crack_map" if d[4] >= 0.5 else "box_head"} for d in dets],
            "ground_truth_xywh": gts})
        print(f"{png}: {w}x{h}, {len(dets)} detections, top: {dets[:1]}")
    for S in (256, 320, 416):
        run, size = ort_runner(os.path.join(a.models, f"crack-detector-{S}.onnx"), threads=1)
        out = run(synthetic_input(S))[0, 0].reshape(-1)
        best = int(np.argmax(out))
        ref["synthetic"].append({
            "model": f"crack-detector-{S}.onnx", "S": S, "cells": S // contract.STRIDE,
            "input": "value(c,y,x) = ((c*7 + y*3 + x*5) % 17) / 16.0, float32, [1,3,S,S]",
            "first_values": [float(v) for v in out[:64]], "sum": float(out.astype(np.float64).sum()),
            "max_index": best, "max_value": float(out[best])})
        print(f"synthetic S={S}: sum {out.sum():.4f}, max {out[best]:.4f} at {best}")
    with open(os.path.join(a.out, "reference.json"), "w") as f:
        json.dump(ref, f, indent=1)
    print("wrote", os.path.join(a.out, "reference.json"))


if __name__ == "__main__":
    main()
