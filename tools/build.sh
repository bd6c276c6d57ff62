#!/usr/bin/env bash
# Configures and builds URLab into ./build (or $URLAB_BUILD_DIR), through ccache when present.
# A development build: warnings are errors (URLAB_WARNINGS_AS_ERRORS=ON; pass
# -DURLAB_WARNINGS_AS_ERRORS=OFF to turn that off). Extra args go to cmake.
# URLAB_BUILD_TARGETS="urlab ..." builds only those targets. The build type is RelWithDebInfo with
# line tables only (-O2 -g1): stack traces keep their lines, and it compiles and links in about a
# third less time than -g (pass -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g" for full debug info).
set -euo pipefail
cd "$(dirname "$0")/.."
# ccache caches files built with a precompiled header only with these (cmake/pch.cmake).
export CCACHE_SLOPPINESS="${CCACHE_SLOPPINESS:-pch_defines,time_macros,include_file_mtime,include_file_ctime}"
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
GEN=()
if command -v ninja >/dev/null 2>&1; then GEN=(-G Ninja); fi
if command -v ccache >/dev/null 2>&1; then GEN+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD_DIR" "${GEN[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DURLAB_WARNINGS_AS_ERRORS=ON "$@"
else
  cmake -S . -B "$BUILD_DIR" "$@" >/dev/null
fi
TARGETS=()
for t in ${URLAB_BUILD_TARGETS:-}; do TARGETS+=(--target "$t"); done
cmake --build "$BUILD_DIR" -j"$(nproc)" "${TARGETS[@]}"
