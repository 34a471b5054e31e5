#!/usr/bin/env bash
# Runs every test of the workspace: unit, property, golden-vector, firmware (mock HAL) and the
# end-to-end tests over real pseudo-terminals.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
python3 crates/protocol/golden/generate.py --check
python3 crates/link/golden/generate.py --check
# The robot's fleet telemetry and Foxglove live-view features are on for the whole run: the end-to-end tests build the
# binaries with it (tests/support), and one feature set means everything compiles once.
cargo test --workspace --features crackbot-cli/telemetry,crackbot-cli/foxglove --locked "$@"
