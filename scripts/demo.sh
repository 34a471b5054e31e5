#!/usr/bin/env bash
# The main job: runs crackbot on the built-in default scene. Until the robot binary exists this is
# the acquisition demo: the simulated finger slides across the default scene's first crack, the
# sensor firmware emulated on this host turns its ADC values into 400 Hz frames on a
# pseudo-terminal, and the acquisition reads them back, records them and prints a summary.
# Extra arguments go to `crackbot demo` (see `--help`).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cargo build --release --locked --quiet -p crackbot-cli --bin crackbot
exec "${CARGO_TARGET_DIR:-target}/release/crackbot" demo "$@"
