#!/usr/bin/env bash
# Checks a mission's ROS 2 bag (`crackbot log to-ros2`) with two readers independent of the
# robot's Rust writer: `rosbags` (pure Python rosbag2 reader and CDR decoder, its typestore built
# from ros/crackbot_msgs/msg/*.msg and ROS 2 Humble's messages) and the `mcap` reader with
# `mcap-ros2-support` (decoding from the definitions stored in the bag). The venv is made on
# first use from scripts/ros2_bag_check.requirements.txt:
#
#   bash scripts/ros2_bag_check.sh out/mission/ros2 out/mission [--json]   # the bag, the mission's folder
#   bash scripts/ros2_bag_check.sh --setup                                  # only make the venv
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
venv="$cache/ros2-venv"
source "$here/pinned_venv.sh"
pinned_venv "$venv" "$here/ros2_bag_check.requirements.txt" ros2_bag_check
case "${1:-}" in
  --setup) exit 0 ;;
  *) exec "$venv/bin/python" "$here/ros2_bag_check.py" --msgs "$here/../ros/crackbot_msgs/msg" "$@" ;;
esac
