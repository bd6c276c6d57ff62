#!/usr/bin/env bash
# with_xvfb.sh SCREEN COMMAND [ARGS...]: runs COMMAND with DISPLAY set to a private Xvfb server
# (SCREEN as WxHxDEPTH) and exits with COMMAND's status; the server is stopped afterwards.
#
# The server picks its own display number (-displayfd), taking the lock for it atomically, so any
# number of these start at once: two test runs sharing the machine, two copies of ctest. xvfb-run
# -a instead picks a number by looking for lock files first, and two of them started together can
# end up on one server; when that server's own run ends, the other's windows fail to open. And
# xvfb-run's server resets whenever its last window closes (see -noreset below).
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: with_xvfb.sh WxHxDEPTH COMMAND [ARGS...]" >&2
  exit 2
fi
screen=$1
shift
dir=$(mktemp -d "${TMPDIR:-/tmp}/urlab_xvfb.XXXXXX")
xvfb_pid=
cleanup() {
  if [ -n "$xvfb_pid" ]; then
    kill "$xvfb_pid" 2>/dev/null || true
    wait "$xvfb_pid" 2>/dev/null || true
  fi
  rm -rf "$dir"
}
trap cleanup EXIT
trap 'exit 143' TERM INT
mkfifo "$dir/display"
# No TCP; the local socket only. The server writes its display number once it accepts clients.
# -noreset: by default an X server resets when its last client disconnects, and a window opened
# during that reset fails ("Failed to open display"): a test suite that closes one window and
# opens the next hits it now and then, more often on a busy machine.
Xvfb -displayfd 3 -screen 0 "$screen" -nolisten tcp -noreset 3>"$dir/display" 2>"$dir/xvfb.log" &
xvfb_pid=$!
number=
read -r -t 60 number <"$dir/display" || true
if [ -z "$number" ]; then
  echo "with_xvfb.sh: Xvfb did not start (its log follows)" >&2
  cat "$dir/xvfb.log" >&2
  exit 1
fi
export DISPLAY=":$number"
unset XAUTHORITY
set +e
"$@"
status=$?
set -e
exit "$status"
