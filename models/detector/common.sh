# Sourced by train.sh, train_effseg.sh and train_tiles.sh: what every training schedule needs first, and the steps they
# share. Sets HERE (this folder, also the working directory), ROOT (the repository), DATA (the crack photos, exported
# as CRACKS_DATA for train.py and eval.py, and as CRACKBOT_CRACKS_DIR for the renderer unless set) and PY (the training
# venv's python; run setup.sh first).
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$HERE"
DATA="${CRACKS_DATA:-$(cd "$HERE/../../../shared/data/cracks" && pwd)}"
export CRACKS_DATA="$DATA"
# The renderer of the training plates (crackbot-lab) takes its crack textures from the same photos.
export CRACKBOT_CRACKS_DIR="${CRACKBOT_CRACKS_DIR:-$DATA}"
PY=.venv/bin/python

# build_lab PROFILE: builds crackbot-lab (debug or release) and sets LAB to its path.
build_lab() {
  local flag=(); [ "$1" = release ] && flag=(--release)
  (cd "$ROOT" && cargo build "${flag[@]}" --quiet -p crackbot-lab)
  LAB="${CARGO_TARGET_DIR:-$ROOT/target}/$1/crackbot-lab"
}

# plates OUT SCENES SEED SUMMARY [PARAMS]: rendered training plates (`sim detector-set`, 2 frames a scene, exact crack
# masks) into OUT, replacing it; the set's JSON summary into SUMMARY. Needs LAB (build_lab).
plates() {
  rm -rf "$1"; mkdir -p "$(dirname "$1")" "$(dirname "$4")"
  "$LAB" sim detector-set --scenes "$2" --frames-per-scene 2 --seed "$3" ${5:+--params "$5"} --out "$1" --json > "$4"
}

# evaluate_sizes MODEL_OUT EVAL: pycocotools metrics of the 320, 256 and 416 exports on each photo set's val split and
# the merged one, and of the 320 export on the paper-style augmented val set, into EVAL/metrics_*.json.
evaluate_sizes() {
  local out=$1 ev=$2 s ds m
  mkdir -p "$ev"
  for s in 320 256 416; do
    m="$out/crack-detector-$s.onnx"
    for ds in crackforest uav75 quaywall; do
      $PY eval.py --model "$m" --ann "$DATA/$ds/val.json" --json-metrics "$ev/metrics_${s}_$ds.json"
    done
    $PY eval.py --model "$m" --ann "$DATA/val_all.json" --root "$DATA" \
        --results "$ev/dets_${s}_val_all.json" --json-metrics "$ev/metrics_${s}_val_all.json"
  done
  $PY augmented_set.py --split val --out "$ev/augval" --seed 0
  $PY eval.py --model "$out/crack-detector-320.onnx" --ann "$ev/augval/annotations.json" \
      --json-metrics "$ev/metrics_320_augval.json"
}
