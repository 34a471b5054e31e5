#!/usr/bin/env bash
# Runs every test of the workspace: unit, property, golden-vector, firmware (mock HAL) and the
# end-to-end tests over real pseudo-terminals.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
python3 crates/protocol/golden/generate.py --check
python3 crates/link/golden/generate.py --check
# The board image for the Arduino Mega 2560 (Debian's rustc 1.63, crate by crate), built beside the
# workspace's build (about 30 s of one core when cold); the tests that run it on the emulated chip
# (tests/board_emulator.rs) wait for it (firmware/image.sh holds a lock while it builds).
image_log="$(mktemp)"
bash firmware/image.sh >"$image_log" 2>&1 &
image_pid=$!
# The robot's fleet telemetry, Foxglove live view and live ROS 2 topics and the controller's ROS 2 arm are on for the whole
# run: the end-to-end tests build the binaries with them (tests/support, FEATURES), and one feature set means
# everything compiles once.
features=crackbot-cli/telemetry,crackbot-cli/foxglove,crackbot-cli/ros2,crackbot-controller/ros2
# cargo-nextest runs the tests of every binary side by side (settings: .config/nextest.toml);
# arguments go to it, e.g. `bash scripts/test.sh -E 'package(crackbot-link)'` or `-E 'test(stop)'`.
# The examples are not built here (25 CPU-seconds cold, no tests in them): CI's clippy stage
# (`--all-targets`) checks that they compile.
cargo nextest run --workspace --lib --bins --tests --features "$features" --locked "$@"
if ! wait "$image_pid"; then
  cat "$image_log" >&2
  echo "firmware/image.sh failed" >&2
  exit 1
fi
echo "board image: $(tail -n 1 "$image_log")"
# nextest does not run doctests; cargo does, when the whole workspace was asked for.
if [ "$#" -eq 0 ]; then
  cargo test --doc --workspace --features "$features" --locked
fi
