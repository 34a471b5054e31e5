"""Test-time flips on the photos: the crack map averaged over the frame and its flips, then the contract's boxes.

    cd models/detector && .venv/bin/python analysis/flip_tta.py [MODEL_FOLDER …]   # default: . crackseg-tiles

Prints merged val mAP@0.5 / AR@100 (pycocotools) for one pass, the horizontal flip (2 passes) and all four
flips (4 passes), at inputs 256 and 320. The box head's boxes, where a model has them, come from the frame
alone. Data: CRACKS_DATA (default ../../../shared/data/cracks), val_all.json only.
"""
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import eval as ev  # noqa: E402

FLIPS = {"one pass": [], "+ horizontal flip": [(-1,)], "+ both flips": [(-1,), (-2,), (-2, -1)]}


def averaged(run, flips):
    """x -> the model's outputs with crack_map averaged over x and its flips (each flipped back)."""
    def go(x):
        out = run(x)
        if not flips:
            return out
        maps = [out["crack_map"]] + [np.flip(run(np.ascontiguousarray(np.flip(x, ax)))["crack_map"], ax)
                                     for ax in flips]
        return {**out, "crack_map": np.mean(maps, axis=0).astype(np.float32)}
    return go


def main():
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    data = os.environ.get("CRACKS_DATA", os.path.join(here, "../../../shared/data/cracks"))
    coco = json.load(open(os.path.join(data, "val_all.json")))
    for folder in sys.argv[1:] or [here, os.path.join(here, "crackseg-tiles")]:
        for size in (256, 320):
            run, s = ev.ort_outputs(os.path.join(folder, f"crack-detector-{size}.onnx"), threads=1)
            for name, flips in FLIPS.items():
                m = ev.coco_metrics(coco, ev.detect_all(averaged(run, flips), coco, data, s))
                print(f"{os.path.basename(os.path.normpath(folder))} {size} {name}: "
                      f"{100 * m['mAP50']:.1f} / {100 * m['AR100']:.1f}", flush=True)


if __name__ == "__main__":
    main()
