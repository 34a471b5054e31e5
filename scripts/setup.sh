#!/usr/bin/env bash
# One-time, idempotent set-up of a fresh Debian machine for crackbot. Sourced by the other scripts;
# safe to run again. Installs only what is missing.
set -euo pipefail

crackbot_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

need_cmd() { command -v "$1" >/dev/null 2>&1; }

# Debian packages the project needs at run or test time. The serial path uses pseudo-terminals from
# the kernel and serialport without libudev. The tactile plots (crates/tactile/src/plots.rs) draw
# their text with DejaVu Sans, read at run time.
apt_packages=(fonts-dejavu-core valgrind)

missing=()
for pkg in "${apt_packages[@]}"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
done
if ((${#missing[@]})); then
  echo "crackbot setup: installing ${missing[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${missing[@]}"
fi

if ! need_cmd cargo; then
  echo "crackbot setup: Rust is not installed. Install it with rustup (https://rustup.rs), stable toolchain." >&2
  exit 1
fi
if ! need_cmd python3; then
  echo "crackbot setup: python3 (3.11) is needed for the golden-vector check." >&2
  exit 1
fi

# Keep build artefacts outside the clone when CRACKBOT_TARGET_DIR is set (CI does this).
if [ -n "${CRACKBOT_TARGET_DIR:-}" ]; then
  export CARGO_TARGET_DIR="$CRACKBOT_TARGET_DIR"
fi
cd "$crackbot_root"
