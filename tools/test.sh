#!/usr/bin/env bash
# The test command: installs dependencies, builds, and runs the whole test suite with ctest,
# then the threaded tests (physics, control, world) again under ThreadSanitizer.
# Set URLAB_SKIP_TSAN=1 to skip the ThreadSanitizer stage.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/build.sh
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
ctest --test-dir "$BUILD_DIR" --output-on-failure -j"$(nproc)" --timeout 900
if [ "${URLAB_SKIP_TSAN:-0}" != "1" ]; then
  echo "== ThreadSanitizer: physics, control and world tests"
  TSAN_DIR="${BUILD_DIR}-tsan"
  GEN=()
  if command -v ninja >/dev/null 2>&1; then GEN=(-G Ninja); fi
  cmake -S . -B "$TSAN_DIR" "${GEN[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DURLAB_SANITIZE=thread \
    -DURLAB_BUILD_BENCH=OFF >/dev/null
  cmake --build "$TSAN_DIR" --target urlab_tests_physics urlab_tests_control urlab_tests_world \
    -j"$(nproc)"
  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
    ctest --test-dir "$TSAN_DIR" -L 'physics|control|world' --output-on-failure -j"$(nproc)" \
    --timeout 900
fi
