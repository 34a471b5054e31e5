#!/usr/bin/env bash
# The crackseg-tiles/ model: the default CrackSeg fine-tuned with the DeepCrack and CRACK500 train tiles added to its
# mix, then a box head of its own: setup, the default's weights rebuilt from its ONNX (analysis/onnx_to_checkpoint.py),
# rendered training plates, one fine-tuning run, export (256/320/416), the box head trained and merged, reference
# outputs, pycocotools evaluation.
#   bash models/detector/train_tiles.sh                             # the committed crackseg-tiles/: 45 + 10 minutes, 2 CPU cores
#   TRAIN_MINUTES=1 BOX_HEAD_MINUTES=0.5 SIM_SCENES=10 MODEL_OUT=/tmp/smoke RUNS=/tmp/smoke/runs bash models/detector/train_tiles.sh
#                                                                   # a short smoke schedule (~6 min), models elsewhere
# MODEL_OUT (default: crackseg-tiles/ beside this script) receives the ONNX files, reference/ and metrics.json; RUNS
# (default: runs) the checkpoints, logs and rendered plates. START (default: the shipped crack-detector-320.onnx) is
# the model whose weights are fine-tuned. Model selection: val_all mAP@0.5 of the real photos (the map's boxes).
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$HERE"
DATA="${CRACKS_DATA:-$(cd "$HERE/../../../shared/data/cracks" && pwd)}"
export CRACKS_DATA="$DATA"
MINUTES=${TRAIN_MINUTES:-45}
BOX_HEAD_MINUTES=${BOX_HEAD_MINUTES:-10}
SIM_SCENES=${SIM_SCENES:-300}
START="${START:-$HERE/crack-detector-320.onnx}"
bash setup.sh
PY=.venv/bin/python
export OMP_NUM_THREADS=2
MODEL_OUT="${MODEL_OUT:-$HERE/crackseg-tiles}"
RUNS="${RUNS:-runs}"
RUN=$RUNS/seg3
SIM=$RUNS/simdata/train
HEAD=$RUN/box_head
EVAL="$RUNS/eval-tiles"
rm -rf "$RUN" "$EVAL"; mkdir -p "$RUN" "$EVAL" "$MODEL_OUT"
(cd "$ROOT" && cargo build --release --quiet -p crackbot-lab)
LAB="${CARGO_TARGET_DIR:-$ROOT/target}/release/crackbot-lab"
rm -rf "$SIM"
"$LAB" sim detector-set --scenes "$SIM_SCENES" --frames-per-scene 2 --seed 1000 --out "$SIM" --json > "$RUNS/simdata.json"
$PY analysis/onnx_to_checkpoint.py --model "$START" --out "$RUN/start.pt"
nice -n 5 $PY train.py --init "$RUN/start.pt" --tiles --sim "$SIM" --minutes "$MINUTES" --lr 1e-3 --seed 2 \
    --eval-every 300 --out "$RUN" | tee "$RUN/stdout.log"
$PY export.py --ckpt "$RUN/best.pt" --sizes 320 256 416 --out "$MODEL_OUT"
bash add_box_head.sh "$MODEL_OUT" "$HEAD" "$BOX_HEAD_MINUTES"
$PY make_reference.py --models "$MODEL_OUT" --out "$MODEL_OUT/reference"
M="$MODEL_OUT/crack-detector-320.onnx"
for ds in crackforest uav75 quaywall; do
  $PY eval.py --model "$M" --ann "$DATA/$ds/val.json" --json-metrics "$EVAL/metrics_320_$ds.json"
done
$PY eval.py --model "$M" --ann "$DATA/val_all.json" --root "$DATA" --json-metrics "$EVAL/metrics_320_val_all.json"
$PY - "$RUN" "$HEAD" "$EVAL" "$MODEL_OUT/metrics.json" <<'PY'
import json, os, sys
run, head, ev, out = sys.argv[1:]
summary = [l for l in open(os.path.join(run, "stdout.log")) if l.startswith("summary: ")][-1]
m = {"training": {"seg3_tiles_finetune": json.loads(summary[len("summary: "):])},
     "box_head": json.load(open(os.path.join(head, "history.json")))["history"][-1],
     "pycocotools_val": {f"320/{ds}": json.load(open(os.path.join(ev, f"metrics_320_{ds}.json")))
                         for ds in ("crackforest", "uav75", "quaywall", "val_all")}}
json.dump(m, open(out, "w"), indent=1)
PY
echo "models:     $MODEL_OUT/crack-detector-{256,320,416}.onnx (crackbot detect --model …, eval-detector --model …)"
echo "reference:  $MODEL_OUT/reference/, metrics: $MODEL_OUT/metrics.json, training logs: $RUN/"
