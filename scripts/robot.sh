#!/usr/bin/env bash
# The main job: the headless robot runs a fused inspection mission on the built-in default scene.
# It starts the simulated manipulator controller (authenticated UDP on loopback) and the simulated
# sensor (the firmware writing 400 Hz frames into a pseudo-terminal) itself, renders the camera
# frame, detects candidate cracks (ONNX), plans slides across them, slides the finger, classifies
# each slide online with the deployed tactile models, and prints which candidates it confirmed.
# The report (report.json) and every recording go to out/mission. Extra arguments go to
# `crackbot-robot` (see `--help`: --scene, --mode tactile|vision|fused, --json, --speedup, faults).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cargo build --release --locked --quiet -p crackbot-cli --bin crackbot-robot
exec "${CARGO_TARGET_DIR:-target}/release/crackbot-robot" "$@"
