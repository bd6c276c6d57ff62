#pragma once
// `urlab bench loop --view`: the loop benchmark (world/loop_bench.h) with the viewer's rendering
// attached: a window on the main thread draws the newest state frame at 60 Hz from its own
// subscription (with the debug capture's post-step callback registered and every debug layer
// on) while the benchmark's trials run on a worker thread; each trial also runs the loop with
// the window drawing, so attached_ratio is the loop's rate with the viewer over without it.
// Thread: main (GLFW); throws Error without a display.
#include <mujoco/mujoco.h>

#include "urlab/viewer/viewer.h"
#include "urlab/world/loop_bench.h"

namespace urlab::viewer {

struct ViewBenchResult {
  world::LoopBenchResult loop;
  std::uint64_t frames = 0;  // frames drawn while the viewer was on
  double fps = 0;            // their rate
};

// `options.attach` and `options.toggle` are the viewer's (any given are replaced).
ViewBenchResult RunLoopBenchWithView(const physics::Model& model, world::LoopBenchOptions options,
                                     const ViewerOptions& view);

}  // namespace urlab::viewer
