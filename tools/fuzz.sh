#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (every library instrumented, ASan + UBSan) into
# build-fuzz (or $URLAB_FUZZ_BUILD_DIR) and runs each for a bounded time on a fresh copy of its
# seed corpus (fuzz/corpus/<target>; the MJCF reader also gets Debian's sample models),
# URLAB_JOBS (default: the cores) at a time.
# Usage: tools/fuzz.sh [SECONDS=60] [TARGET...]
#   targets: fuzz_mjcf_reader fuzz_scene fuzz_net_control fuzz_step_request fuzz_shm_channel
#   fuzz_recording fuzz_mesh
#   (default: all)
# Exits non-zero when a target crashes (or leaks, or times out on one input), printing the
# reproducer's path; rerun one with: build-fuzz/fuzz/<target> <reproducer>.
# Run corpora, logs and reproducers stay under the build folder (not in git).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-60}"
shift || true
ALL=(fuzz_mjcf_reader fuzz_scene fuzz_net_control fuzz_step_request fuzz_shm_channel fuzz_recording
  fuzz_mesh)
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then TARGETS=("${ALL[@]}"); fi
for t in "${TARGETS[@]}"; do
  case " ${ALL[*]} " in *" $t "*) ;; *) echo "fuzz.sh: unknown target '$t' (${ALL[*]})" >&2; exit 2;; esac
done
BUILD_DIR="${URLAB_FUZZ_BUILD_DIR:-build-fuzz}"
GEN=()
if command -v ninja >/dev/null 2>&1; then GEN=(-G Ninja); fi
LAUNCHER=()
if command -v ccache >/dev/null 2>&1; then LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" "${GEN[@]}" "${LAUNCHER[@]}" \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DURLAB_BUILD_FUZZ=ON -DURLAB_BUILD_TESTS=OFF \
    -DURLAB_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$BUILD_DIR" --target "${TARGETS[@]}" -j"${URLAB_JOBS:-$(nproc)}"

# The network targets feed decoders with limits of their own (request size, payload size): the
# target prints its limit (URLAB_FUZZ_PRINT_MAX_LEN=1) and is fuzzed with inputs up to it, so the
# limits and everything below them are reached. The file-format targets take up to 64 KiB.
max_len() {
  case "$1" in
    fuzz_net_control | fuzz_step_request | fuzz_shm_channel) URLAB_FUZZ_PRINT_MAX_LEN=1 "$BUILD_DIR/fuzz/$1" ;;
    *) echo 65536 ;;
  esac
}

# fuzz_one TARGET: runs one target; its summary line goes to its work folder's `result` and its
# exit status is the fuzzer's.
fuzz_one() {
  local t=$1 work len rc cov runs repro
  work="$BUILD_DIR/fuzz-run/$t"
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  cp fuzz/corpus/"$t"/* "$work/corpus/"
  if [ "$t" = fuzz_mjcf_reader ]; then
    cp examples/models/*.xml tests/data/mjcf/corpus/*.xml "$work/corpus/" 2>/dev/null || true
  fi
  len=$(max_len "$t")
  echo "== fuzz $t for ${SECONDS_TO_RUN} s, inputs up to $len bytes (seeds: $(ls "$work/corpus" | wc -l))"
  set +e
  "$BUILD_DIR/fuzz/$t" -max_total_time="$SECONDS_TO_RUN" -max_len="$len" \
    -timeout=20 -rss_limit_mb=4096 -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" "$work/corpus" >"$work/log" 2>&1
  rc=$?
  set -e
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$work/log" | tail -1 || true)
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$work/log" | grep -oE '[0-9]+$' || true)
  if [ $rc -ne 0 ]; then
    grep -E 'ERROR|SUMMARY|runtime error|Test unit written' "$work/log" | head -20 || true
    repro=$(grep -oE 'Test unit written to [^ ]+' "$work/log" | tail -1 | sed 's/Test unit written to //' || true)
    echo "fuzz: $t FAILED (exit $rc); reproducer: ${repro:-none} (log: $work/log)"
    echo "$t: FAILED, ${cov:-no coverage line}; reproducer ${repro:-none}" >"$work/result"
  else
    echo "$t: ok, ${cov:-?} after ${runs:-?} runs" >"$work/result"
  fi
  return $rc
}

# The targets run URLAB_JOBS at a time (each fuzzer is one process on one core).
status=0
PARALLEL="${URLAB_JOBS:-$(nproc)}"
PIDS=()
for t in "${TARGETS[@]}"; do
  fuzz_one "$t" &
  PIDS+=($!)
  if [ "${#PIDS[@]}" -ge "$PARALLEL" ]; then
    wait "${PIDS[0]}" || status=1
    PIDS=("${PIDS[@]:1}")
  fi
done
for pid in "${PIDS[@]}"; do wait "$pid" || status=1; done
SUMMARY=()
for t in "${TARGETS[@]}"; do
  SUMMARY+=("$(cat "$BUILD_DIR/fuzz-run/$t/result" 2>/dev/null || echo "$t: FAILED before fuzzing")")
done
echo "== fuzz summary (${SECONDS_TO_RUN} s each)"
for s in "${SUMMARY[@]}"; do echo "  $s"; done
exit $status
