#!/usr/bin/env bash
# Runs the board image on an emulated ATmega2560 (simavr) with its UART on a new pseudo-terminal:
# prints that terminal's path as its first line, then streams at 400 Hz until stopped (Ctrl-C,
# SIGTERM), and prints its counters (timing, bytes, resets) as JSON on standard error at the end.
#   usage: bash firmware/emulate.sh [--trace FILE.csv] [--no-flow-control] [--stats FILE] [ELF]
#   --trace FILE.csv    what the four amplifiers output: raw counts D1,D2,D3,P, one 1/400 s sample a
#                       line, looped (default: firmware/emulator/default-slide.csv, the simulator's
#                       first slide on the default scene; make others with
#                       `crackbot-sensor-emulator --write-trace`)
#   --no-flow-control   the Mega's own USB bridge (no CTS: bytes the host does not take are lost)
#                       instead of an FTDI-style adapter with RTS/CTS (the default)
#   --stats FILE        also write the counters to FILE, every emulated second
#   ELF                 the image (default: built by firmware/image.sh)
# While it runs: kill -USR1 PID resets the chip (power-on), kill -USR2 PID corrupts the next byte.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/toolchain.sh"
trace="$firmware_dir/emulator/default-slide.csv"
args=()
elf=""
while (($#)); do
  case "$1" in
    --trace) trace="${2:?--trace needs a file}"; shift 2 ;;
    --no-flow-control) args+=("$1"); shift ;;
    --stats) args+=("$1" "${2:?--stats needs a file}"); shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    -*) echo "emulate.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) elf="$1"; shift ;;
  esac
done
harness="$firmware_out/emulator/crackbot-mega2560-emulator"
source_c="$firmware_dir/emulator/mega2560.c"
(
  flock 9
  if [ ! -x "$harness" ] || [ "$source_c" -nt "$harness" ]; then
    mkdir -p "$(dirname "$harness")"
    # shellcheck disable=SC2046 # pkg-config's flags are separate words
    gcc -O2 -Wall -Wextra -Werror -o "$harness.tmp" "$source_c" $(pkg-config --cflags --libs simavr)
    mv "$harness.tmp" "$harness"
  fi
) 9>"$firmware_out/.emulator.lock"
if [ -z "$elf" ]; then
  elf="$(bash "$firmware_dir/image.sh" | tail -n 1)"
fi
exec "$harness" "${args[@]}" "$trace" "$elf"
