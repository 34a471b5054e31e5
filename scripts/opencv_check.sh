#!/usr/bin/env bash
# Calibrates with OpenCV (its Python binding, an implementation independent of crackbot-calib)
# from the same matched points, for the tests to compare (scripts/opencv_check.py). The venv is
# made on first use from scripts/opencv_check.requirements.txt:
#
#   bash scripts/opencv_check.sh calibrate VIEWS.json WIDTH HEIGHT   # prints the fit as JSON
#   bash scripts/opencv_check.sh images FOLDER TARGET.toml            # OpenCV's detection too
#   bash scripts/opencv_check.sh --setup                             # only make the venv
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/opencv-venv"
source "$here/pinned_venv.sh"
pinned_venv "$venv" "$here/opencv_check.requirements.txt" opencv_check
case "${1:-}" in
  --setup) exit 0 ;;
  *) exec "$venv/bin/python" "$here/opencv_check.py" "$@" ;;
esac
