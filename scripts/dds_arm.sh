#!/usr/bin/env bash
# Plays an independent ROS 2 arm over DDS with Eclipse Cyclone DDS's Python binding
# (scripts/dds_arm.py), so tests can prove that crackbot's ROS 2 backend drives a real DDS peer. No
# ROS installation is needed: the arm speaks ROS 2's DDS topic and type names directly. The venv is
# made on first use from scripts/dds_arm.requirements.txt:
#
#   bash scripts/dds_arm.sh --seconds 10 --record /tmp/targets.txt   # see --help for the rest
#   bash scripts/dds_arm.sh --setup                                  # only make the venv
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/dds-venv"
source "$here/pinned_venv.sh"
pinned_venv "$venv" "$here/dds_arm.requirements.txt" dds_arm
case "${1:-}" in
  --setup) exit 0 ;;
  *) exec "$venv/bin/python" "$here/dds_arm.py" "$@" ;;
esac
