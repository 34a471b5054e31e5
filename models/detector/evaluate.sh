#!/usr/bin/env bash
# Every figure of MODEL_CARD.md by crackbot's own (Rust) evaluator, release build, one ONNX Runtime thread:
#   bash models/detector/evaluate.sh            # the default (crackseg-tiles/): models/detector/out/rust/*.json and the trade-off tables
#   MODELS=models/detector OUT=/tmp/eval-scratch bash models/detector/evaluate.sh
#                                               # the same figures for another folder of crack-detector-{256,320,416}.onnx
#   DETECTORS=onnx TRADEOFF_THREADS= …          # the model's accuracy alone (no edge baseline, no timing runs)
# The val splits of the photos and of the DeepCrack/CRACK500 tiles; unseen rendered scenes of three families (seeds 900000.. with the training
# family's parameters, 950000.. with eval/unseen-layout-b.toml, 970000.. with eval/unseen-layout-c.toml), never rendered for training; 8 frames of the built-in
# default scene; the edge baseline on the same sets; mAP@0.5 vs input size vs ms at 1 and 2 threads.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
C="${CRACKS_DATA:-$(cd "$ROOT/../shared/data/cracks" && pwd)}"
# The unseen scenes' renderer takes its crack textures from the same photos.
export CRACKBOT_CRACKS_DIR="${CRACKBOT_CRACKS_DIR:-$C}"
TILES="${CRACK_TILES_DATA:-$(cd "$ROOT/../shared/data/cracks-tiles" && pwd)}"
OUT="${OUT:-$HERE/out/rust}"
MODELS="$(cd "${MODELS:-$HERE/crackseg-tiles}" && pwd)"
M320="$MODELS/crack-detector-320.onnx"
[ -f "$M320" ] || { echo "evaluate.sh: no crack-detector-320.onnx in $MODELS" >&2; exit 2; }
mkdir -p "$OUT"
(cd "$ROOT" && cargo build --release --quiet -p crackbot-cli -p crackbot-lab)
T="${CARGO_TARGET_DIR:-$ROOT/target}/release"
B="$T/crackbot"
L="$T/crackbot-lab"
SIM="$HERE/out/sim"
[ -d "$SIM/unseen-a" ] || "$L" sim detector-set --scenes 20 --frames-per-scene 2 --seed 900000 --out "$SIM/unseen-a" --json > /dev/null
[ -d "$SIM/unseen-b" ] || "$L" sim detector-set --params "$HERE/eval/unseen-layout-b.toml" --scenes 20 --frames-per-scene 2 \
    --seed 950000 --out "$SIM/unseen-b" --json > /dev/null
[ -d "$SIM/unseen-c" ] || "$L" sim detector-set --params "$HERE/eval/unseen-layout-c.toml" --scenes 20 --frames-per-scene 2 \
    --seed 970000 --out "$SIM/unseen-c" --json > /dev/null
[ -d "$SIM/default" ] || "$B" sim render --out "$SIM/default" --frames 8 > /dev/null
for det in ${DETECTORS:-onnx classical}; do
  MODEL_ARG=(); [ "$det" = onnx ] && MODEL_ARG=(--model "$M320")
  for ds in crackforest uav75 quaywall; do
    "$L" eval-detector --coco "$C/$ds/val.json" --detector $det "${MODEL_ARG[@]}" --json > "$OUT/${det}_$ds.json"
  done
  "$L" eval-detector --coco "$C/val_all.json" --detector $det "${MODEL_ARG[@]}" --json > "$OUT/${det}_val_all.json"
  for ds in deepcrack crack500; do
    "$L" eval-detector --coco "$TILES/$ds/val.json" --detector $det "${MODEL_ARG[@]}" --json > "$OUT/${det}_tiles_$ds.json"
  done
  for s in unseen-a unseen-b unseen-c; do
    "$L" eval-detector --coco "$SIM/$s/annotations.json" --detector $det "${MODEL_ARG[@]}" --json > "$OUT/${det}_$s.json"
  done
  "$L" eval-detector --coco "$SIM/default/coco.json" --images "$SIM/default/images" --detector $det "${MODEL_ARG[@]}" --json \
      > "$OUT/${det}_default_scene.json"
done
for th in ${TRADEOFF_THREADS-1 2}; do
  "$L" detector-tradeoff --coco "$C/val_all.json" --threads $th --out "$OUT/tradeoff-val_all-${th}thread" \
      --models "$MODELS"/crack-detector-{256,320,416}.onnx
  "$L" detector-tradeoff --coco "$SIM/unseen-a/annotations.json" --threads $th --no-classical \
      --out "$OUT/tradeoff-unseen-a-${th}thread" --models "$MODELS"/crack-detector-{256,320,416}.onnx
done
python3 - "$OUT" <<'PY'
import json, sys, glob, os
out = sys.argv[1]
print(f"{'set':34s} {'mAP':>6s} {'mAP50':>6s} {'AR100':>6s} {'ODS0':>6s} {'ODS2':>6s} {'ODS5':>6s} {'masks':>9s} {'found':>9s} {'decoys':>7s} {'1 piece':>9s} {'split':>5s} {'joined':>6s}")
for p in sorted(glob.glob(os.path.join(out, "*.json"))):
    r = json.load(open(p))
    pix = {x["tolerance_px"]: x["ods"]["f1"] for x in r.get("pixel", [])}
    cr = r.get("cracks")
    masks = f"{cr['found']}/{cr['cracks']}" if cr else ""
    sc = r.get("scene")
    found = f"{sc['found']}/{sc['cracks']}" if sc else ""
    dec = f"{sc['decoys_proposed']}/{sc['decoys']}" if sc else ""
    pc = (sc or {}).get("pieces")
    one = f"{pc['one_piece']}/{pc['cracks']}" if pc else ""
    split = str(pc["in_pieces"]) if pc else ""
    joined = str(pc["joined"]) if pc else ""
    f = lambda v: f"{100*v:6.1f}" if v is not None else "     -"
    print(f"{os.path.basename(p)[:-5]:34s} {f(r['map'])} {f(r['map50'])} {f(r['ar100'])} {f(pix.get(0.0))} {f(pix.get(2.0))} {f(pix.get(5.0))} {masks:>9s} {found:>9s} {dec:>7s} {one:>9s} {split:>5s} {joined:>6s}")
PY
