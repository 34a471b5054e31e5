#!/usr/bin/env bash
# Creates models/detector/.venv and installs requirements.txt into it (idempotent).
set -euo pipefail
cd "$(dirname "$0")"
PY=${PYTHON:-python3.11}
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
if ! .venv/bin/python - <<'PYEOF' 2>/dev/null
import sys
from importlib.metadata import version
for line in open("requirements.txt"):
    line = line.strip()
    if not line or line.startswith("#"):
        continue
    name, want = line.split("==")
    if version(name) != want:
        sys.exit(1)
PYEOF
then
  .venv/bin/pip install -r requirements.txt
fi
echo "venv ready: $(pwd)/.venv"
