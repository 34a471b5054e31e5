#!/usr/bin/env bash
# A virtual X display for the operator app's window test (crates/operator/tests/window.rs) and
# for running the app on a machine with no screen. Installs what it needs on first use
# (Xvfb, Mesa's llvmpipe software GL driver, the X client libraries winit loads); idempotent.
#
#   scripts/xvfb.sh install            # install only
#   scripts/xvfb.sh run CMD [ARGS...]  # run CMD on a fresh display (1280x800x24), then stop it
set -euo pipefail

xvfb_packages=(xvfb xauth libgl1 libegl1 libgl1-mesa-dri libglx-mesa0 libx11-xcb1 libxcursor1
  libxrandr2 libxi6 libxkbcommon-x11-0 fonts-dejavu-core)

xvfb_install() {
  local missing=() pkg
  for pkg in "${xvfb_packages[@]}"; do
    dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg")
  done
  if ((${#missing[@]})); then
    echo "crackbot xvfb: installing ${missing[*]}" >&2
    local sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
  fi
}

xvfb_run() {
  xvfb_install
  # A free display number: no lock file and no socket.
  local n=99
  while [ -e "/tmp/.X$n-lock" ] || [ -e "/tmp/.X11-unix/X$n" ]; do n=$((n + 1)); done
  Xvfb ":$n" -screen 0 1280x800x24 -nolisten tcp >/dev/null 2>&1 &
  xvfb_pid=$!
  trap 'kill "$xvfb_pid" 2>/dev/null || true; wait "$xvfb_pid" 2>/dev/null || true' EXIT
  local i
  for i in $(seq 1 100); do
    [ -e "/tmp/.X11-unix/X$n" ] && break
    kill -0 "$xvfb_pid" 2>/dev/null || { echo "crackbot xvfb: Xvfb :$n did not start" >&2; exit 1; }
    sleep 0.1
  done
  export DISPLAY=":$n"
  # The software GL driver; no Wayland here.
  export LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe
  unset WAYLAND_DISPLAY
  export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
  chmod 0700 "$XDG_RUNTIME_DIR"
  "$@"
}

case "${1:-}" in
  install) xvfb_install ;;
  run) shift; [ $# -gt 0 ] || { echo "usage: $0 run CMD [ARGS...]" >&2; exit 2; }; xvfb_run "$@" ;;
  *) echo "usage: $0 install | run CMD [ARGS...]" >&2; exit 2 ;;
esac
