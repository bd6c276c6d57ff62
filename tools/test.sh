#!/usr/bin/env bash
# The test command (CI runs it): installs dependencies, builds, runs the whole test suite with
# ctest, then more stages, each printing its wall time, and a table of them at the end:
#   main        GCC build (RelWithDebInfo: -O2, line tables) of everything + every test (ctest);
#               the same build is the one installed by the install stage
#   tsan        ThreadSanitizer (-O1, unity build): the core, physics, control, world, replay, ops,
#               net and client tests
#   asan        clang build with AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer's
#               coverage (-O1, assertions on, unity build): the CLI, the fuzz targets, and the
#               decoders' and model readers' tests plus the fast unit tests (core, document, mjcf,
#               replay, control), which it runs
#   install     cmake --install of the main build; every installed header compiles on its own;
#               examples/find_package built against it
#   fuzz        every libFuzzer target (built by asan) for URLAB_FUZZ_SECONDS (default 30) s, as
#               many at once as there are cores
# Every stage builds with warnings as errors (URLAB_WARNINGS_AS_ERRORS=ON). A user's plain
# `cmake -DCMAKE_BUILD_TYPE=Release` build keeps warnings as warnings.
# Build folders: $URLAB_BUILD_DIR (default build) and beside it ${URLAB_BUILD_DIR}-tsan and
# -asan. ccache is used when present. Skip stages with
# URLAB_SKIP_STAGES="tsan asan ..." (URLAB_SKIP_TSAN=1 still skips tsan).
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
export URLAB_BUILD_DIR="$BUILD_DIR"
JOBS="${URLAB_JOBS:-$(nproc)}"
SKIP=" ${URLAB_SKIP_STAGES:-} "
if [ "${URLAB_SKIP_TSAN:-0}" = "1" ]; then SKIP="$SKIP tsan "; fi
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
# ccache caches files built with a precompiled header only with these (cmake/pch.cmake).
export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
GEN=()
if command -v ninja >/dev/null 2>&1; then GEN=(-G Ninja); fi
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

TIMINGS=()
TOTAL_START=$(date +%s)
summary() {
  local rc=$?
  echo "== stage timings"
  printf '  %-10s %6s  %s\n' stage seconds result
  for t in "${TIMINGS[@]}"; do printf '  %s\n' "$t"; done
  printf '  %-10s %6s\n' total "$(($(date +%s) - TOTAL_START))"
  return $rc
}
trap summary EXIT
# stage NAME COMMAND...: runs COMMAND, prints "== stage NAME: N s" and records it.
stage() {
  local name=$1
  shift
  if [[ "$SKIP" == *" $name "* ]]; then
    TIMINGS+=("$(printf '%-10s %6s  %s' "$name" - skipped)")
    return 0
  fi
  echo "== stage $name: start"
  local start rc
  start=$(date +%s)
  # A subshell outside any `||`, so that `set -e` holds inside the stage's commands.
  set +e
  (
    set -e
    "$@"
  )
  rc=$?
  set -e
  local took=$(($(date +%s) - start))
  echo "== stage $name: $took s"
  TIMINGS+=("$(printf '%-10s %6s  %s' "$name" "$took" "$([ $rc -eq 0 ] && echo ok || echo "FAILED ($rc)")")")
  return $rc
}
configure() {  # configure DIR [cmake args...] (once; later runs keep the cache)
  local dir=$1
  shift
  if [ ! -f "$dir/CMakeCache.txt" ]; then
    cmake -S . -B "$dir" "${GEN[@]}" "${LAUNCHER[@]}" -DURLAB_WARNINGS_AS_ERRORS=ON "$@" >/dev/null
  fi
}

# ctest DIR [args...]: ctest with every failing test's output, then (on a failure) the failed
# assertions alone, last: a long log's middle may be cut where it is shown.
run_ctest() {
  local dir=$1
  shift
  ctest --test-dir "$dir" --output-on-failure "$@" && return 0
  local rc=$?
  echo "== failed assertions and errors (from $dir/Testing/Temporary/LastTest.log):"
  grep -E -B3 -A12 '(^|: )Failure$|^\[  FAILED  \] [A-Za-z]|Traceback \(most recent|Error: |^ERROR|Sanitizer' \
    "$dir/Testing/Temporary/LastTest.log" | head -200 || true
  return $rc
}

# Sanitizer builds at -O1 (what the sanitizers' documentation suggests): about 40% less compile
# time than -O2 with UBSan's checks, stack traces keep their lines. They are unity builds
# (URLAB_UNITY_BUILD): a cold sanitizer build takes about half the CPU time of one file at a time.
SANITIZER_OPT="-O1 -g1 -DNDEBUG"

main_stage() {
  # tools/build.sh's build (-O2 -g1: line tables only), the one tools/demo.sh makes too, so that
  # either command after the other reuses the objects.
  tools/build.sh
  run_ctest "$BUILD_DIR" -j"$JOBS" --timeout 900
  # The viewer end to end on a private virtual display (the viewer.xvfb ctest entry runs its unit
  # tests the same way): a window, the panel, a screenshot taken at t=0.5 s.
  tests/support/with_xvfb.sh 1280x1024x24 "$BUILD_DIR/urlab" view examples/scenes/two_arms.yaml \
    --no-network --debug-all --screenshot "$BUILD_DIR/viewer-smoke.png" --at 0.5
}

tsan_stage() {
  local dir="${BUILD_DIR}-tsan"
  configure "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DURLAB_SANITIZE=thread -DURLAB_BUILD_BENCH=OFF \
    -DURLAB_UNITY_BUILD=ON "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$SANITIZER_OPT"
  # The net tests include the Python client's end-to-end test, which runs the urlab binary.
  cmake --build "$dir" -j"$JOBS" --target urlab urlab_tests_core urlab_tests_physics \
    urlab_tests_control urlab_tests_world urlab_tests_replay urlab_tests_ops urlab_tests_net \
    urlab_tests_client urlab_tests_embed
  # The Python end-to-end tests whose subject is the Python side (examples, gait, the gymnasium
  # contract, Dask with plain and batched servers, the learning example, port choice) run in the
  # main stage only; the ones that load the server's threads (client, shared memory, hardening,
  # batched environments, latency) run here too.
  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$PWD/tests/tsan.supp" \
    run_ctest "$dir" -L 'core|physics|control|world|replay|ops|net|client|embed' \
    -E 'python_examples_e2e|gait_e2e|gym_env_e2e|cluster_(batch_)?e2e|learn_reach_smoke|ports_e2e' \
    -j"$JOBS" --timeout 900
}

asan_stage() {  # also CI's clang build and its build with assertions on
  local dir="${BUILD_DIR}-asan"
  # URLAB_BUILD_FUZZ instruments every library for ASan, UBSan and libFuzzer's coverage (the
  # tests link the sanitizer runtimes alone), so one build serves these tests and the fuzz stage.
  CC=clang CXX=clang++ configure "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DURLAB_BUILD_FUZZ=ON \
    -DURLAB_BUILD_BENCH=OFF -DURLAB_UNITY_BUILD=ON "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1"
  cmake --build "$dir" -j"$JOBS" --target urlab urlab_tests_core urlab_tests_mjcf \
    urlab_tests_document urlab_tests_replay urlab_tests_control urlab_tests_embed \
    fuzz_mjcf_reader fuzz_scene fuzz_net_control fuzz_step_request fuzz_shm_channel \
    fuzz_recording fuzz_mesh
  ASAN_OPTIONS="detect_leaks=1 abort_on_error=1" UBSAN_OPTIONS="print_stacktrace=1" \
    run_ctest "$dir" -L 'core|mjcf|document|replay|control|embed' \
    -j"$JOBS" --timeout 900
}

check_client_links() {  # check_client_links BINARY...: fails when one links a server library
  local bin libs
  for bin in "$@"; do
    libs=$(ldd "$bin")
    if grep -Ei 'assimp|embree|libGL|libEGL|OSMesa|mujoco|glfw' <<<"$libs"; then
      echo "$bin links a server-side library (above)" >&2
      return 1
    fi
    echo "$bin: $(grep -c '=>' <<<"$libs") shared libraries, none of the server's"
  done
}

# check_headers_alone PREFIX: every installed header compiles as the only include of a file
# (-fsyntax-only, warnings as errors), so each one includes what it uses. The builds themselves
# cannot show it: precompiled headers and the sanitizer stages' unity batches supply includes.
check_headers_alone() {
  local prefix=$1 list rc=0
  list=$(mktemp)
  (cd "$prefix/include" && find urlab -name '*.h' | sort) >"$list"
  # shellcheck disable=SC2016
  xargs -P "$JOBS" -I{} sh -c 'printf "#include <%s>\n" "$1" |
    g++ -std=c++20 -fsyntax-only -Wall -Wextra -Werror -I"$2/include" -x c++ - ||
    { echo "$1 does not compile on its own" >&2; exit 255; }' sh {} "$prefix" <"$list" || rc=$?
  [ $rc -eq 0 ] && echo "$(wc -l <"$list") installed headers compile on their own"
  rm -f "$list"
  return $rc
}

install_stage() {
  local dir="$BUILD_DIR" prefix example
  prefix=$(mktemp -d)
  example=$(mktemp -d)
  cmake --install "$dir" --prefix "$prefix" >/dev/null
  echo "installed into $prefix: $(find "$prefix" -type f | wc -l) files"
  check_headers_alone "$prefix"
  cmake -S examples/find_package -B "$example" "${GEN[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$prefix" "${LAUNCHER[@]}" >/dev/null
  cmake --build "$example" -j"$JOBS"
  "$example/urlab_find_package_example" examples/models/pendulum_arm.xml
  # It registers no subsystem's scene sections: a scene with `cameras:` is refused at that line,
  # naming the registration a program adds to parse it (README, "Install").
  if "$example/urlab_find_package_example" examples/scenes/go2_camera.yaml 2>"$example/err.txt"; then
    echo "the example accepted a scene with a section it did not register" >&2
    return 1
  fi
  grep -F "'cameras:' is a section of urlab::camera (call urlab::camera::RegisterSceneSections())" \
    "$example/err.txt"
  "$example/urlab_client_only_example"
  # A client program links the wire format and ZeroMQ only: neither MuJoCo's model code nor
  # assimp, Embree or a renderer (GL, EGL, OSMesa) may reach it.
  check_client_links "$example/urlab_client_only_example" "$BUILD_DIR/example_cpp_controller"
  "$prefix/bin/urlab" --version
  # The in-process batch from Python, its library found beside the installed urlab (../lib): the
  # client is a copy outside the checkout, so the checkout's build folder is not looked in.
  cp -r clients/python "$example/client"
  PATH="$prefix/bin:$PATH" URLAB_CLIENT_COPY="$example/client" .venv/bin/python - <<'PY'
import os
import sys
sys.path.insert(0, os.environ["URLAB_CLIENT_COPY"])
import numpy as np
from urlab_client import UrlabVectorEnv
with UrlabVectorEnv.in_process("examples/scenes/humanoid_pd.yaml", 2) as envs:
    envs.reset(seed=0)
    obs, *_ = envs.step(np.zeros((2, 21)))
    library = envs.envs[0]._lib._name
    print("in-process batch from", library, obs["qpos"].shape)
    assert library.startswith(os.environ["PATH"].split(":")[0].rsplit("/", 1)[0]), library
PY
  rm -rf "$prefix" "$example"
}

fuzz_stage() {
  URLAB_FUZZ_BUILD_DIR="${BUILD_DIR}-asan" URLAB_JOBS="$JOBS" \
    tools/fuzz.sh "${URLAB_FUZZ_SECONDS:-30}"
}

stage main main_stage
stage tsan tsan_stage
stage asan asan_stage
stage install install_stage
stage fuzz fuzz_stage
