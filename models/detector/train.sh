#!/usr/bin/env bash
# Retrain the crack detector (CrackSeg, a crack-map model) from scratch: setup, rendered training plates,
# two training stages, export (256/320/416), reference outputs, evaluation.
#   bash models/detector/train.sh                                   # the committed model: 20 + 50 minutes, 2 CPU cores
#   TRAIN_MINUTES=1 STAGE2_MINUTES=2 SIM_SCENES=20 bash models/detector/train.sh   # a short smoke schedule (~5 min)
# Stage 1 trains on the real photos only (crackforest and uav75 masks, quaywall boxes); stage 2 restarts the cosine
# from stage 1's best weights with the simulator's rendered plates added (`crackbot-lab sim detector-set`, scene
# seeds 1000.., exact crack masks). Model selection: val_all mAP@0.5 of the real photos. The unseen rendered scenes
# of the evaluation (seeds 900000..) are never rendered here.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$HERE"
DATA="${CRACKS_DATA:-$(cd "$HERE/../../../shared/data/cracks" && pwd)}"
export CRACKS_DATA="$DATA"
MINUTES=${TRAIN_MINUTES:-20}
STAGE2_MINUTES=${STAGE2_MINUTES:-50}
SIM_SCENES=${SIM_SCENES:-300}
bash setup.sh
PY=.venv/bin/python
export OMP_NUM_THREADS=2
RUN=runs/seg1
RUN2=runs/seg2
SIM=runs/simdata/train
rm -rf "$RUN" "$RUN2" "$SIM"; mkdir -p "$RUN" "$RUN2" out
(cd "$ROOT" && cargo build --quiet -p crackbot-lab)
LAB="${CARGO_TARGET_DIR:-$ROOT/target}/debug/crackbot-lab"
"$LAB" sim detector-set --scenes "$SIM_SCENES" --frames-per-scene 2 --seed 1000 --out "$SIM" --json > "$RUN/simdata.json"
nice -n 5 $PY train.py --minutes "$MINUTES" --eval-every 300 --out "$RUN" | tee "$RUN/stdout.log"
nice -n 5 $PY train.py --init "$RUN/best.pt" --sim "$SIM" --minutes "$STAGE2_MINUTES" --lr 2e-3 --seed 1 \
    --eval-every 300 --out "$RUN2" | tee "$RUN2/stdout.log"
$PY export.py --ckpt "$RUN2/best.pt" --sizes 320 256 416 --out "$HERE"
$PY make_reference.py --models "$HERE" --out "$HERE/reference"
for S in 320 256 416; do
  for ds in crackforest uav75 quaywall; do
    $PY eval.py --model crack-detector-$S.onnx --ann $DATA/$ds/val.json --json-metrics out/metrics_${S}_$ds.json
  done
  $PY eval.py --model crack-detector-$S.onnx --ann $DATA/val_all.json --root $DATA \
      --results out/dets_${S}_val_all.json --json-metrics out/metrics_${S}_val_all.json
done
$PY augmented_set.py --split val --out out/augval --seed 0
$PY eval.py --model crack-detector-320.onnx --ann out/augval/annotations.json --json-metrics out/metrics_320_augval.json
$PY collect_metrics.py
echo "models:     $HERE/crack-detector-{256,320,416}.onnx"
echo "reference:  $HERE/reference/"
echo "metrics:    $HERE/metrics.json, training logs: $HERE/$RUN/ and $HERE/$RUN2/"
