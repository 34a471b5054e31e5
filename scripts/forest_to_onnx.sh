#!/usr/bin/env bash
# Exports a crackbot forest file to ONNX (scripts/forest_to_onnx.py), in a venv of its own that this
# script makes on first use from scripts/forest_to_onnx.requirements.txt (idempotent; re-installed when a
# pin changes):
#
#   bash scripts/forest_to_onnx.sh MODEL.forest MODEL.onnx
#   bash scripts/forest_to_onnx.sh --setup          # only make the venv (scripts/setup.sh does this)
#
# The venv: $CRACKBOT_CACHE_DIR/forest-onnx-venv (default ~/.cache/crackbot/forest-onnx-venv), outside the
# clone like ONNX Runtime's (scripts/setup.sh), so every checkout and `cargo test` find it.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/forest-onnx-venv"
req="$here/forest_to_onnx.requirements.txt"

source "$here/pinned_venv.sh"
pinned_venv "$venv" "$req" forest_to_onnx
if [ "${1:-}" = "--setup" ]; then
  exit 0
fi
exec "$venv/bin/python" "$here/forest_to_onnx.py" "$@"
