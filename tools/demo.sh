#!/usr/bin/env bash
# The main job: installs dependencies, builds, and runs URLab on the bundled example.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/build.sh
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
OUT="${URLAB_DEMO_OUT:-out/demo}"
mkdir -p "$OUT"
echo "== urlab compile examples/models/pendulum_arm.xml (debug XML and MJB into $OUT)"
"$BUILD_DIR/urlab" compile examples/models/pendulum_arm.xml \
  --save-xml "$OUT/scene_compiled.xml" --save-mjb "$OUT/scene_compiled.mjb"
echo "== user-built articulation (C++ API)"
"$BUILD_DIR/example_build_articulation"
echo "== urlab run examples/scenes/two_arms.yaml --duration 5 (two arms held raised under PD)"
"$BUILD_DIR/urlab" run examples/scenes/two_arms.yaml --duration 5
