"""Failure analysis, part 2: why each missed val box is missed, for a trained model.

For every ground-truth box of the val splits, the best detection (IoU) at the detect threshold is found; a box
with IoU < 0.5 is put in one class:
  * not_seen   - no crack cell of the map falls inside the box (the model does not see the crack);
  * split      - detections cover the box in pieces: >= 2 detections lie mostly (>= 50% of their area) inside it;
  * merged     - the best detection is much larger than the box (area > 2x, the box inside it): the crack was
                 joined with other cracks or with false positives by the dilation;
  * partial    - one detection, too small (seen only in part);
  * other      - the rest.
Writes a JSON summary and, with --sheet, a contact sheet of the missed boxes (ground truth green, detections red).

  .venv/bin/python analysis/failures.py --model crack-detector-320.onnx [--sheet out/failures.png]
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, HERE)
import contract  # noqa: E402
from eval import load_rgb, ort_runner  # noqa: E402

DATA = os.environ.get("CRACKS_DATA", os.path.normpath(os.path.join(HERE, "../../../shared/data/cracks")))


def iou(a, b):
    ix = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    iy = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = ix * iy
    ua = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return inter / ua if ua > 0 else 0.0


def area(b):
    return max(0.0, b[2] - b[0]) * max(0.0, b[3] - b[1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default=os.path.join(HERE, "crack-detector-320.onnx"))
    ap.add_argument("--threshold", type=float, default=0.25)
    ap.add_argument("--sheet", default=None)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    run, size = ort_runner(a.model)
    summary, tiles = {}, []
    for ds in ("crackforest", "uav75", "quaywall"):
        coco = json.load(open(os.path.join(DATA, ds, "val.json")))
        counts = {"boxes": 0, "found": 0, "not_seen": 0, "split": 0, "merged": 0, "partial": 0, "other": 0}
        for im in coco["images"]:
            img = load_rgb(os.path.join(DATA, ds, im["file_name"]))
            h, w = img.shape[:2]
            x, s = contract.letterbox(img, size)
            prob = run(x)[0, 0]
            dets = [d for d in contract.map_to_detections(prob, w, h, size) if d[4] >= a.threshold]
            pimg = contract.map_to_image(prob, w, h, size)
            for an in (an for an in coco["annotations"] if an["image_id"] == im["id"]):
                bx, by, bw, bh = an["bbox"]
                g = (bx, by, bx + bw, by + bh)
                counts["boxes"] += 1
                best = max(dets, key=lambda d: iou(d, g), default=None)
                if best is not None and iou(best, g) >= 0.5:
                    counts["found"] += 1
                    continue
                inside = pimg[int(by):int(by + bh) + 1, int(bx):int(bx + bw) + 1]
                if inside.size == 0 or inside.max() < contract.MAP_THRESHOLD:
                    why = "not_seen"
                else:
                    pieces = [d for d in dets if area(d) > 0 and
                              area((max(d[0], g[0]), max(d[1], g[1]), min(d[2], g[2]), min(d[3], g[3]))) >= 0.5 * area(d)]
                    if len(pieces) >= 2:
                        why = "split"
                    elif best is not None and area(best) > 2 * area(g) and iou(best, g) > 0 and \
                            best[0] <= g[0] + 2 and best[1] <= g[1] + 2 and best[2] >= g[2] - 2 and best[3] >= g[3] - 2:
                        why = "merged"
                    elif best is not None and area(best) < area(g):
                        why = "partial"
                    else:
                        why = "other"
                counts[why] += 1
                if a.sheet and len(tiles) < 24:
                    t = Image.fromarray(img).convert("RGB")
                    dr = ImageDraw.Draw(t)
                    dr.rectangle(g, outline=(0, 255, 0), width=3)
                    for d in dets:
                        dr.rectangle(d[:4], outline=(255, 0, 0), width=2)
                    dr.text((4, 4), f"{ds} {why}", fill=(255, 255, 0))
                    t.thumbnail((256, 256))
                    tiles.append(t)
        summary[ds] = counts
        print(ds, counts)
    if a.sheet and tiles:
        cols = 6
        rows = (len(tiles) + cols - 1) // cols
        sheet = Image.new("RGB", (cols * 256, rows * 256), (0, 0, 0))
        for i, t in enumerate(tiles):
            sheet.paste(t, ((i % cols) * 256, (i // cols) * 256))
        os.makedirs(os.path.dirname(os.path.abspath(a.sheet)), exist_ok=True)
        sheet.save(a.sheet)
        print("wrote", a.sheet)
    if a.json:
        json.dump(summary, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
