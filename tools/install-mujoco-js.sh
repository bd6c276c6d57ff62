#!/usr/bin/env bash
# Installs the MuJoCo 3.x reference used by tests/mjcf/reference3x_test.cc: the official MuJoCo
# WebAssembly build from the npm registry (package mujoco-js, pinned), run by Node.js.
#
#   bash tools/install-mujoco-js.sh DIR      (e.g. build/mujoco-js; never the source tree)
#
# Idempotent: does nothing when DIR already holds the pinned version. Needs node and npm
# (Debian: apt-get install nodejs npm) and access to the npm registry; exits non-zero with a
# message saying which is missing.
set -euo pipefail

PACKAGE=mujoco-js
VERSION=0.0.7  # MuJoCo 3.3.8

if [ $# -ne 1 ] || [ -z "$1" ]; then
  echo "usage: $0 DIR   (a folder of the build, e.g. build/mujoco-js)" >&2
  exit 2
fi
DIR=$1
SRC_ROOT=$(cd "$(dirname "$0")/.." && pwd)

for tool in node npm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "install-mujoco-js: '$tool' not found; install Node.js and npm first" \
      "(Debian: apt-get install nodejs npm)" >&2
    exit 1
  fi
done

DIR=$(realpath -m "$DIR")
case "$DIR/" in
  "$SRC_ROOT"/build*/*) ;;  # a build folder inside the checkout is fine
  "$SRC_ROOT"/*)
    echo "install-mujoco-js: refusing to install into the source tree ($DIR); use a build" \
      "folder such as build/mujoco-js" >&2
    exit 2
    ;;
esac
mkdir -p "$DIR"

MANIFEST="$DIR/node_modules/$PACKAGE/package.json"
installed_version() {
  [ -f "$MANIFEST" ] || return 0
  node -e 'process.stdout.write(require(process.argv[1]).version)' "$MANIFEST" 2>/dev/null || true
}

if [ "$(installed_version)" = "$VERSION" ] &&
  [ -f "$DIR/node_modules/$PACKAGE/dist/mujoco_wasm.js" ]; then
  echo "install-mujoco-js: $PACKAGE@$VERSION already installed in $DIR"
  exit 0
fi

LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
if ! npm install --prefix "$DIR" --no-audit --no-fund --no-save --loglevel=error \
  "$PACKAGE@$VERSION" >"$LOG" 2>&1; then
  cat "$LOG" >&2
  if grep -qiE 'ENOTFOUND|ECONNREFUSED|ECONNRESET|ETIMEDOUT|EAI_AGAIN|network|proxy' "$LOG"; then
    echo "install-mujoco-js: npm could not reach the registry ($(npm config get registry))" \
      "to download $PACKAGE@$VERSION; check the network or the npm proxy settings" >&2
  else
    echo "install-mujoco-js: npm install $PACKAGE@$VERSION into $DIR failed (see above)" >&2
  fi
  exit 1
fi

if [ "$(installed_version)" != "$VERSION" ]; then
  echo "install-mujoco-js: npm finished but $MANIFEST does not hold version $VERSION" >&2
  exit 1
fi
echo "install-mujoco-js: installed $PACKAGE@$VERSION (MuJoCo 3.x WebAssembly) in $DIR"
