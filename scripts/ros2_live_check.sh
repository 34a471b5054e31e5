#!/usr/bin/env bash
# Subscribes to a running mission's live ROS 2 topics with Eclipse Cyclone DDS's Python binding
# (scripts/ros2_live_check.py), in the venv of the DDS arm (scripts/dds_arm.requirements.txt):
#
#   bash scripts/ros2_live_check.sh --domain 0 [--late 3]    # prints READY, then one JSON line
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/dds-venv"
source "$here/pinned_venv.sh"
pinned_venv "$venv" "$here/dds_arm.requirements.txt" dds_arm
exec "$venv/bin/python" "$here/ros2_live_check.py" "$@"
