#!/usr/bin/env bash
# Installs every build, test and runtime dependency of URLab from Debian bookworm's archive.
# Run as root (or through sudo). Safe to run again.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libmujoco-dev libmujoco-samples libqhull-dev
  libtinyxml2-dev libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libeigen3-dev libzmq3-dev cppzmq-dev libmsgpack-cxx-dev libzstd-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev ccache
  python3 python3-zmq python3-msgpack python3-numpy
  # urlab_client.cluster and `urlab sweep`: Dask distributed, YAML
  python3-distributed python3-yaml
  # examples/python/learn_reach.py (PPO through the vector env; CI runs a short smoke of it)
  python3-torch
  libglfw3-dev libimgui-dev libstb-dev libgl1-mesa-dri xvfb xauth ffmpeg
  libassimp-dev libembree-dev libbullet-extras-dev libbullet-dev
  # cameras: off-screen rendering (EGL surfaceless on Mesa, OSMesa fallback)
  libegl-dev libegl1-mesa-dev libosmesa6-dev
)
# Everything present already (a second run, a prepared machine): no apt-get, no network.
PRESENT=$(dpkg-query -W -f='${db:Status-Abbrev}\n' "${PACKAGES[@]}" 2>/dev/null | grep -c '^ii' || true)
if [ "$PRESENT" -eq "${#PACKAGES[@]}" ]; then
  echo "install-deps: ${#PACKAGES[@]} packages present"
  exit 0
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${PACKAGES[@]}" >/dev/null
echo "install-deps: ${#PACKAGES[@]} packages present"
