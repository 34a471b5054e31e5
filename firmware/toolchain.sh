#!/usr/bin/env bash
# The board image's and the board emulator's tools, from Debian's registry, installed on first use
# (sourced by image.sh and emulate.sh; scripts/setup.sh installs the same list). Sets
# firmware_out, where both put what they build.
#   rustc, rust-src   Debian's Rust 1.63 with its LLVM AVR back end, and the `core` sources
#   gcc-avr, avr-libc, binutils-avr   the linker, start-up code, memcpy & co., objcopy, size
#   simavr, libsimavr-dev, libelf-dev, pkg-config, gcc   the ATmega2560 emulator and its harness
set -euo pipefail
firmware_apt_packages=(rustc rust-src gcc-avr avr-libc binutils-avr simavr libsimavr-dev libelf-dev
  pkg-config gcc)
firmware_dir="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
firmware_out="${CARGO_TARGET_DIR:-$firmware_dir/../target}/firmware"
mkdir -p "$firmware_out"

firmware_missing=()
for pkg in "${firmware_apt_packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || firmware_missing+=("$pkg")
done
if ((${#firmware_missing[@]})); then
  (
    # One installer at a time (tests build the image from several processes).
    flock 9
    echo "crackbot firmware: installing ${firmware_missing[*]} (Debian packages)" >&2
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${firmware_missing[@]}" >&2
  ) 9>"$firmware_out/.apt.lock"
fi
