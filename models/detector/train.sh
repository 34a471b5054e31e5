#!/usr/bin/env bash
# Retrain the crack detector (CrackSeg, a crack-map model) from scratch: setup, rendered training plates,
# two training stages, export (256/320/416), the box head on the frozen features merged into each, reference
# outputs, evaluation.
#   bash models/detector/train.sh                                   # the committed model: 20 + 55 + 25 minutes, 2 CPU cores
#   TRAIN_MINUTES=1 STAGE2_MINUTES=2 BOX_HEAD_MINUTES=1 SIM_SCENES=20 MODEL_OUT=/tmp/smoke RUNS=/tmp/smoke/runs bash models/detector/train.sh
#                                                                   # a short smoke schedule (~12 min), models elsewhere
# MODEL_OUT (default: this folder) receives the ONNX files, reference/ and metrics.json; RUNS (default: runs)
# the checkpoints, logs and rendered plates.
# Stage 1 trains on the real photos only (crackforest and uav75 masks, quaywall boxes); stage 2 restarts the cosine
# from stage 1's best weights with the simulator's rendered plates added (`crackbot-lab sim detector-set`, scene
# seeds 1000.., exact crack masks). Model selection: val_all mAP@0.5 of the real photos. The unseen rendered scenes
# of the evaluation (seeds 900000..) are never rendered here.
set -euo pipefail
source "$(dirname "$0")/common.sh"
MINUTES=${TRAIN_MINUTES:-20}
STAGE2_MINUTES=${STAGE2_MINUTES:-55}
BOX_HEAD_MINUTES=${BOX_HEAD_MINUTES:-25}
SIM_SCENES=${SIM_SCENES:-300}
bash setup.sh
export OMP_NUM_THREADS=2
MODEL_OUT="${MODEL_OUT:-$HERE}"
RUNS="${RUNS:-runs}"
RUN=$RUNS/seg1
RUN2=$RUNS/seg2
SIM=$RUNS/simdata/train
EVAL="$MODEL_OUT/out"
rm -rf "$RUN" "$RUN2" "$SIM"; mkdir -p "$RUN" "$RUN2" "$EVAL"
build_lab debug
plates "$SIM" "$SIM_SCENES" 1000 "$RUN/simdata.json"
nice -n 5 $PY train.py --minutes "$MINUTES" --eval-every 300 --out "$RUN" | tee "$RUN/stdout.log"
nice -n 5 $PY train.py --init "$RUN/best.pt" --sim "$SIM" --minutes "$STAGE2_MINUTES" --lr 2e-3 --seed 1 \
    --eval-every 300 --out "$RUN2" | tee "$RUN2/stdout.log"
$PY export.py --ckpt "$RUN2/best.pt" --sizes 320 256 416 --out "$MODEL_OUT"
# The box head (boxes in the photos' own convention, MODEL_CARD.md "The box head"): trained on the frozen features of
# the 320 export on the photos' train boxes, its final weights merged into every size (crack_map unchanged).
HEAD=$RUNS/box_head
bash add_box_head.sh "$MODEL_OUT" "$HEAD" "$BOX_HEAD_MINUTES"
$PY make_reference.py --models "$MODEL_OUT" --out "$MODEL_OUT/reference"
evaluate_sizes "$MODEL_OUT" "$EVAL"
$PY collect_metrics.py --runs "$RUNS" --eval "$EVAL" --out "$MODEL_OUT/metrics.json"
echo "models:     $MODEL_OUT/crack-detector-{256,320,416}.onnx"
echo "reference:  $MODEL_OUT/reference/"
echo "metrics:    $MODEL_OUT/metrics.json, training logs: $RUN/, $RUN2/ and $HEAD/"
