#!/usr/bin/env bash
# Creates benches/.venv-bench (ignored) and installs benches/requirements.txt into it; idempotent, and
# re-installs when a pin changes. For benches/sklearn_ort.py and benches/sklearn_fit.py.
set -euo pipefail
cd "$(dirname "$0")"
source "$(pwd)/../scripts/pinned_venv.sh"
pinned_venv "$(pwd)/.venv-bench" "$(pwd)/requirements.txt" setup_venv "${PYTHON:-python3}"
echo "venv ready: $(pwd)/.venv-bench"
