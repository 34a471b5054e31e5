# Sourced by the scripts that run Python tools: `pinned_venv VENV REQUIREMENTS NAME [PYTHON]` makes
# the venv VENV (with PYTHON, default python3) from the pinned REQUIREMENTS file on first use, and
# installs again when a pin changes.
pinned_venv() {
  local venv="$1" req="$2" name="$3" python="${4:-python3}"
  if [ -x "$venv/bin/python" ] && "$venv/bin/python" - "$req" <<'PYEOF' 2>/dev/null; then
import sys
from importlib.metadata import version
for line in open(sys.argv[1]):
    line = line.strip()
    if not line or line.startswith("#"):
        continue
    name, want = line.split("==")
    if version(name) != want:
        sys.exit(1)
PYEOF
    return 0
  fi
  echo "$name: installing $(grep -v '^#' "$req" | tr '\n' ' ')into $venv" >&2
  mkdir -p "$(dirname "$venv")"
  [ -x "$venv/bin/python" ] || "$python" -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$req" >&2
}
