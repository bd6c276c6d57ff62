#!/usr/bin/env bash
# Builds the libFuzzer target for the MJCF reader with clang and runs it for a bounded time.
# Usage: tools/fuzz.sh [SECONDS=60]. Seeds: the test corpus and Debian's sample models.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_TO_RUN="${1:-60}"
BUILD_DIR=build-fuzz
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DURLAB_BUILD_FUZZ=ON -DURLAB_BUILD_TESTS=OFF -DURLAB_BUILD_BENCH=OFF >/dev/null
fi
cmake --build "$BUILD_DIR" --target fuzz_mjcf_reader -j"$(nproc)"
mkdir -p fuzz/corpus-run
cp -n tests/data/mjcf/corpus/*.xml tests/data/mjcf/broken/*.xml fuzz/corpus-run/ 2>/dev/null || true
cp -n /usr/share/mujoco/model/*/*.xml fuzz/corpus-run/ 2>/dev/null || true
"$BUILD_DIR/fuzz/fuzz_mjcf_reader" -max_total_time="$SECONDS_TO_RUN" -max_len=65536 \
  -timeout=10 -rss_limit_mb=4096 fuzz/corpus-run
