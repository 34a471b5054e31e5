#!/usr/bin/env bash
# Checks a mission's MCAP log with the Python `mcap` package, an implementation independent of
# the robot's (scripts/mcap_check.py), or watches a live mission over the Foxglove WebSocket
# protocol (scripts/foxglove_live_check.py). The venv is made on first use from
# scripts/mcap_check.requirements.txt:
#
#   bash scripts/mcap_check.sh out/mission                 # the folder `crackbot run` wrote
#   bash scripts/mcap_check.sh --live ws://127.0.0.1:8765  # a mission served with --foxglove
#   bash scripts/mcap_check.sh --setup                     # only make the venv (scripts/setup.sh does)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/mcap-venv"
source "$here/pinned_venv.sh"
pinned_venv "$venv" "$here/mcap_check.requirements.txt" mcap_check
case "${1:-}" in
  --setup) exit 0 ;;
  --live) shift; exec "$venv/bin/python" "$here/foxglove_live_check.py" "$@" ;;
  *) exec "$venv/bin/python" "$here/mcap_check.py" "$@" ;;
esac
