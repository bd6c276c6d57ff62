#pragma once
// The profiler (F3) and the info overlay (F2): what the physics thread spends per step (MuJoCo's
// timers: step, forward, collision, constraint solver) and the problem's size (contacts,
// constraint rows, solver iterations), read on the physics thread by a read-only Inspect command
// every 0.1 s while either is shown (never from live mjData on this thread), plotted over time
// with mjr_figure as simulate does.
//
// Threading contract: main thread, except the Inspect command's function (physics thread), which
// hands its sample over under the profiler's own mutex.
#include <mujoco/mujoco.h>

#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>

#include "urlab/physics/engine.h"

namespace urlab::viewer::internal {

struct ProfileSample {
  double time = 0;                                                      // simulation time
  double step_ms = 0, forward_ms = 0, collision_ms = 0, solver_ms = 0;  // per step since the last
  int ncon = 0, nefc = 0, iterations = 0;
  std::uint64_t steps = 0;  // steps the timings average over
};

class Profiler {
 public:
  Profiler();
  ~Profiler();
  // Asks the physics thread for a sample when the last is 0.1 s old (main thread, each frame
  // while shown). MuJoCo's timers run from the first request on (mjcb_time, set on the physics
  // thread).
  void Request(physics::PhysicsEngine& engine);
  // The newest sample (nullopt before the first), and takes new ones into the history.
  std::optional<ProfileSample> Latest();
  std::size_t samples() const { return history_.size(); }
  // Draws the timing and size figures into `viewport`.
  void Draw(const mjrRect& viewport, const mjrContext* con);

 private:
  struct Shared {
    std::mutex mutex;
    std::deque<ProfileSample> fresh;
    // Physics-thread side: the timer totals at the previous sample.
    double prev[mjNTIMER] = {};
    int prev_n = 0;
  };
  std::shared_ptr<Shared> shared_;
  std::deque<ProfileSample> history_;
  std::chrono::steady_clock::time_point last_request_{};
  std::unique_ptr<mjvFigure> timing_, size_;
};

}  // namespace urlab::viewer::internal
