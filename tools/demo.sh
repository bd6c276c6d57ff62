#!/usr/bin/env bash
# The main job: installs dependencies, builds, and runs URLab on the bundled example scene.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/build.sh
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
exec "$BUILD_DIR/urlab" compile /usr/share/mujoco/model/humanoid/humanoid.xml "$@"
