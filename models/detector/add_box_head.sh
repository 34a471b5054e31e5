#!/usr/bin/env bash
# Trains the box head (analysis/box_head.py; MODEL_CARD.md "The box head") on the frozen features of
# MODEL_OUT/crack-detector-320.onnx and merges it into the 320, 256 and 416 models of MODEL_OUT, in place (their
# crack_map unchanged). Used by train.sh and train_tiles.sh:
#   bash add_box_head.sh MODEL_OUT HEAD_DIR MINUTES [CROPS]
set -euo pipefail
cd "$(dirname "$0")"
MODEL_OUT=$1; HEAD=$2; MINUTES=$3; CROPS=${4:-2}
PY=.venv/bin/python
mkdir -p "$HEAD"
nice -n 5 $PY analysis/box_head.py --model "$MODEL_OUT/crack-detector-320.onnx" --minutes "$MINUTES" \
    --crops "$CROPS" --channels 32 --seed 0 --out "$HEAD" | tee "$HEAD/box_head.log"
for S in 320 256 416; do
  $PY analysis/merge_box_head.py --model "$MODEL_OUT/crack-detector-$S.onnx" --size $S --head "$HEAD/box_head.pt" \
      --channels 32 --out "$MODEL_OUT/crack-detector-$S.onnx" --skip-eval
done
