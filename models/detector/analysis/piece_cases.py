"""Contact sheet of the cracks that did not come out as one piece, on rendered frames.

For each crack that `crackbot-lab eval-detector` counts as "in pieces" or "joined" (its `pieces.cases`),
a crop of the frame with the true centre lines (green: that crack, yellow: other cracks, magenta:
printed decoys) and the pieces the robot would touch (red axis, white touch point).

    models/detector/.venv/bin/python models/detector/analysis/piece_cases.py SET EVAL_JSON DETECT_JSON OUT.png

SET is a `sim detector-set` folder (features.json, images/), EVAL_JSON the output of
`crackbot-lab eval-detector --coco SET/annotations.json --json`, DETECT_JSON the output of
`crackbot detect --json SET/images/*.png` with the same model.
"""

import json
import os
import sys

from PIL import Image, ImageDraw


def load(path):
    with open(path) as f:
        return json.load(f)


TILE = 220  # a case's crop, pixels square
GAP = 2  # between crops on the sheet
COLS = 6


def draw_case(img, boxes, case, pieces, size=TILE):
    """The crop of `img` around `case`'s crack with the true centre lines of `boxes` and the `pieces` drawn."""
    x, y, w, h = case["bbox"]
    cx, cy = x + w / 2, y + h / 2
    half = max(w, h) / 2 + 30
    left, top = cx - half, cy - half
    crop = img.crop((int(left), int(top), int(cx + half), int(cy + half))).convert("RGB")
    s = size / crop.width
    crop = crop.resize((size, size))
    d = ImageDraw.Draw(crop)

    def xy(p):
        return ((p[0] - left) * s, (p[1] - top) * s)

    for b in boxes:
        path = [p for p in (b.get("path_px") or []) if p is not None]
        if len(path) < 2:
            continue
        mine = b["kind"] == "crack" and [round(v) for v in b["bbox"]] == [round(v) for v in case["bbox"]]
        colour = (0, 255, 0) if mine else (255, 255, 0) if b["kind"] == "crack" else (255, 0, 255)
        d.line([xy(p) for p in path], fill=colour, width=1)
    for p in pieces:
        d.line([xy(p["axis"][0]), xy(p["axis"][1])], fill=(255, 0, 0), width=2)
        tx, ty = xy(p["touch"])
        d.ellipse((tx - 3, ty - 3, tx + 3, ty + 3), outline=(255, 255, 255), width=2)
    kind = "joined" if case["pieces"] == 0 else f"{case['pieces']} pieces"
    width = case.get("width_mm")
    d.text((3, 3), f"{os.path.basename(case['file'])} {kind} {width or 0:.2f} mm", fill=(255, 255, 255))
    return crop


def main(set_dir, eval_json, detect_json, out_png):
    features = {os.path.basename(i["file_name"]): i for i in load(os.path.join(set_dir, "features.json"))["images"]}
    pieces = {}
    for im in load(detect_json)["images"]:
        name = os.path.basename(im["file"])
        pieces[name] = [p for det in im["detections"] for p in det.get("pieces_px", [])]
    cases = load(eval_json)["scene"]["pieces"]["cases"]
    tiles = []
    for case in cases:
        name = os.path.basename(case["file"])
        img = Image.open(os.path.join(set_dir, "images", name))
        tiles.append(draw_case(img, features[name]["boxes"], case, pieces.get(name, [])))
    step = TILE + GAP
    rows = max(1, (len(tiles) + COLS - 1) // COLS)
    sheet = Image.new("RGB", (COLS * step, rows * step))
    for k, t in enumerate(tiles):
        sheet.paste(t, ((k % COLS) * step, (k // COLS) * step))
    sheet.save(out_png)
    print(f"{len(tiles)} cases -> {out_png}")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
