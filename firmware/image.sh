#!/usr/bin/env bash
# Builds the board image: crackbot's sampling firmware for the Arduino Mega 2560 (ATmega2560),
# from firmware/mega2560 with Debian's rustc 1.63 (installed on first use). Prints the ELF's path
# as its last line; the Intel HEX file for avrdude lies beside it. Quick when nothing changed.
#   usage: bash firmware/image.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
(
  flock 9
  python3 "$firmware_dir/mega2560/build.py" "$firmware_out/mega2560"
) 9>"$firmware_out/.image.lock"
