#!/usr/bin/env bash
# The main job: installs dependencies, builds what it runs (the urlab CLI and one C++ example, not
# the tests or benchmarks), runs the bundled two-arm scene and a Go2 trotting under its gait
# controller (a client sets its twist) and leaves something to look at: a
# screenshot of the viewer on a virtual X server (xvfb-run, no display needed) and a video of the
# recorded run rendered off-screen (urlab render: frame-exact, 30 frames per simulated second
# however slow the machine), named in the last lines beside the run's summary.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
BUILD_DIR="${URLAB_BUILD_DIR:-build}"
URLAB_BUILD_TARGETS="urlab example_build_articulation" tools/build.sh
OUT="${URLAB_DEMO_OUT:-out/demo}"
mkdir -p "$OUT"
URLAB="$BUILD_DIR/urlab"
SCENE=examples/scenes/two_arms.yaml
echo "== urlab compile examples/models/pendulum_arm.xml (debug XML and MJB into $OUT)"
"$URLAB" compile examples/models/pendulum_arm.xml \
  --save-xml "$OUT/pendulum_arm_compiled.xml" --save-mjb "$OUT/pendulum_arm_compiled.mjb"
echo "== user-built articulation (C++ API)"
"$BUILD_DIR/example_build_articulation"
echo "== urlab run $SCENE --duration 5 --record (two arms held raised under PD)"
"$URLAB" run "$SCENE" --duration 5 --no-network --record "$OUT/two_arms.urrec" | tee "$OUT/run.log"
echo "== the viewer on $SCENE (a virtual X server), and the recording rendered off-screen"
# Software rendering on a virtual display; --at counts simulated seconds.
xvfb-run -a -s "-screen 0 1280x1024x24" "$URLAB" view "$SCENE" --no-network --debug-all \
  --screenshot "$OUT/two_arms.png" --at 1.5 >"$OUT/view.log" 2>&1
"$URLAB" render "$OUT/two_arms.urrec" --video "$OUT/two_arms.mp4" --width 640 --height 480 \
  >"$OUT/render.log" 2>&1
echo "== a Go2 trotting under its gait controller (a client sets its twist), rendered tracking it"
rm -f "$OUT/go2.json"
"$URLAB" run examples/scenes/go2_network.yaml --duration 8 --ports auto --no-cameras \
  --announce "$OUT/go2.json" --record "$OUT/go2_walk.urrec" >"$OUT/go2_run.log" 2>&1 &
RUN=$!
.venv/bin/python examples/python/twist.py "$OUT/go2.json" dog --vx 0.6
wait "$RUN"
"$URLAB" render "$OUT/go2_walk.urrec" --video "$OUT/go2_walk.mp4" --camera track:dog_base \
  --shadows --width 640 --height 360 >"$OUT/go2_render.log" 2>&1
echo "== done"
grep '^summary:' "$OUT/run.log"
echo "screenshot: $OUT/two_arms.png"
echo "video:      $OUT/two_arms.mp4 (the recording $OUT/two_arms.urrec at 30 frames/s)"
echo "video:      $OUT/go2_walk.mp4 (the Go2 trotting at 0.6 m/s, the recording $OUT/go2_walk.urrec)"
