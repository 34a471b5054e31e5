#!/usr/bin/env bash
# Retrain the crack detector from scratch: setup, train, export (256/320/416), reference outputs, evaluation.
#   bash models/detector/train.sh            # two stages, 39 + 30 minutes on 2 CPU cores
# Stage 1 trains from scratch on a cosine schedule over TRAIN_MINUTES; stage 2 restarts the cosine
# (lower peak LR, another augmentation seed) from stage 1's best weights for STAGE2_MINUTES.
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
cd "$HERE"
DATA="${CRACKS_DATA:-$(cd "$HERE/../../../shared/data/cracks" && pwd)}"
export CRACKS_DATA="$DATA"
MINUTES=${TRAIN_MINUTES:-39}
STAGE2_MINUTES=${STAGE2_MINUTES:-30}
bash setup.sh
PY=.venv/bin/python
export OMP_NUM_THREADS=2
RUN=runs/train
RUN2=runs/train2
rm -rf "$RUN" "$RUN2"; mkdir -p "$RUN" "$RUN2" out
nice -n 10 $PY train.py --minutes "$MINUTES" --eval-every 180 --out "$RUN" | tee "$RUN/stdout.log"
nice -n 10 $PY train.py --init "$RUN/best.pt" --minutes "$STAGE2_MINUTES" --lr 1e-3 --seed 1 \
    --eval-every 180 --out "$RUN2" | tee "$RUN2/stdout.log"
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
echo "metrics:    $HERE/out/metrics_*.json, training log: $HERE/$RUN/"
