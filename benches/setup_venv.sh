#!/usr/bin/env bash
# Creates benches/.venv-bench (ignored) and installs benches/requirements.txt into it; idempotent, and
# re-installs when a pin changes. For benches/sklearn_ort.py and benches/sklearn_fit.py.
set -euo pipefail
cd "$(dirname "$0")"
if [ ! -x .venv-bench/bin/python ]; then
  "${PYTHON:-python3}" -m venv .venv-bench
fi
if ! .venv-bench/bin/python - <<'PYEOF' 2>/dev/null
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
  .venv-bench/bin/pip install --quiet --disable-pip-version-check -r requirements.txt
fi
echo "venv ready: $(pwd)/.venv-bench"
