#!/usr/bin/env bash
# Installs every build, test and runtime dependency of URLab: Debian bookworm's packages, then the
# project's Python environment .venv (Debian's python3 with its system packages, plus the exact
# PyPI versions of tools/requirements.txt, MuJoCo's wheel among them: CMake builds against it).
# Run as root (or through sudo) for the Debian part. Safe to run again: nothing is fetched when
# everything is present.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libqhull-dev
  libtinyxml2-dev libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libeigen3-dev libzmq3-dev cppzmq-dev libmsgpack-cxx-dev libzstd-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev ccache
  python3 python3-venv python3-zmq python3-msgpack python3-numpy
  # urlab_client.cluster and `urlab sweep`: Dask distributed, YAML
  python3-distributed python3-yaml
  # examples/python/learn_reach.py (PPO through the vector env; CI runs a short smoke of it)
  python3-torch
  # examples/python/sb3_ppo.py: stable-baselines3's own dependencies (its logger imports
  # matplotlib and pandas); `urlab bench peers`: EnvPool needs matplotlib and imageio pillow
  # (Debian's keep pip from bringing a matplotlib that wants numpy 2 over Debian's numpy)
  python3-matplotlib python3-pandas python3-pil
  libglfw3-dev libimgui-dev libstb-dev libgl1-mesa-dri xvfb xauth ffmpeg
  libassimp-dev libembree-dev libbullet-extras-dev libbullet-dev
  # cameras: off-screen rendering (EGL surfaceless on Mesa, OSMesa fallback)
  libegl-dev libegl1-mesa-dev libosmesa6-dev
)
# Everything present already (a second run, a prepared machine): no apt-get, no network.
PRESENT=$(dpkg-query -W -f='${db:Status-Abbrev}\n' "${PACKAGES[@]}" 2>/dev/null | grep -c '^ii' || true)
if [ "$PRESENT" -ne "${#PACKAGES[@]}" ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${PACKAGES[@]}" >/dev/null
fi
echo "install-deps: ${#PACKAGES[@]} packages present"

# The Python environment: made once; the pinned packages installed again only when
# tools/requirements.txt or tools/requirements-nodeps.txt changed (their hash is kept in the
# environment).
cd "$(dirname "$0")/.."
VENV=.venv
REQ=tools/requirements.txt
NODEPS=tools/requirements-nodeps.txt  # after REQ, with --no-deps (the reason is in the file)
STAMP="$VENV/.urlab-requirements.sha256"
# Every requirement is an exact version (name==X.Y.Z), so every machine installs the same build.
PINNED='^[A-Za-z0-9._-]+==[^=<>!~*,; ]+$'
if UNPINNED=$(grep -hvE '^[[:space:]]*(#|$)' "$REQ" "$NODEPS" | grep -vE "$PINNED"); then
  echo "install-deps: requirements without an exact version (name==version): $UNPINNED" >&2
  exit 1
fi
WANT=$(cat "$REQ" "$NODEPS" | sha256sum | cut -d' ' -f1)
if [ ! -x "$VENV/bin/python" ]; then
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi
if [ "$(cat "$STAMP" 2>/dev/null)" != "$WANT" ]; then
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-input -r "$REQ"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-input --no-deps \
    -r "$NODEPS"
  echo "$WANT" >"$STAMP"
fi
echo "install-deps: $VENV ($("$VENV/bin/python" -c 'import mujoco; print("mujoco", mujoco.__version__)'))"
