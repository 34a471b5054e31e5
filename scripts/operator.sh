#!/usr/bin/env bash
# The operator's desktop app (crates/operator): with no arguments it runs missions in-process on
# the built-in default scene (simulated arm and sensor, no network); `--source live` watches and
# commands robots over Zenoh, `--source replay DIR` shows a saved mission (`crackbot run --out
# DIR`). Extra arguments go to `crackbot-operator` (see `--help`). Needs a display; on a machine
# without one, `bash scripts/xvfb.sh run bash scripts/operator.sh --start --measure-frames 600
# --screenshot shot.png` runs it on a virtual one.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
  echo "crackbot operator: no display (DISPLAY and WAYLAND_DISPLAY are unset); on a headless machine use" >&2
  echo "  bash scripts/xvfb.sh run bash scripts/operator.sh --start --measure-frames 600 --screenshot shot.png" >&2
  exit 1
fi
cargo build --release --locked --quiet -p crackbot-operator
exec "${CARGO_TARGET_DIR:-target}/release/crackbot-operator" "$@"
