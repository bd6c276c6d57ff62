#pragma once
// StepCostEstimate: what one physics step of a lockstep window costs in wall time, as the step
// server's I/O thread measures it, to decide whether a window is short enough to step on that
// thread itself (StepServer::StepHere, BatchStepHere) or goes to the physics thread.
//
// A window measured slow because this thread lost its core for a while (a busy machine) must not
// hand every later window to the physics thread: the estimate only ever learns from windows it
// lets run here, so it would never come down again. Two rules keep it honest:
// - a sample counts at most kOutlier times the current estimate (a preempted window moves it by
//   a bounded factor; a step that really became dearer still moves it there within a few
//   windows);
// - a window declined for its cost lowers the estimate by kDecay, never below the cheapest step
//   measured, so that a declined size is tried again now and then (a window larger than the
//   budget at that cheapest cost is never tried).
//
// Thread: the step server's I/O thread only.
#include <algorithm>

namespace urlab::net {

class StepCostEstimate {
 public:
  static constexpr double kOutlier = 4;
  static constexpr double kDecay = 0.97;

  // Whether `n` steps fit in `budget` seconds (before any measurement: n == 1 only).
  bool Affordable(int n, double budget) {
    if (seconds_ <= 0) return n == 1;
    if (n * seconds_ <= budget) return true;
    seconds_ = std::max(cheapest_, seconds_ * kDecay);  // declined; a later window may try
    return false;
  }
  // A window ran: its wall seconds per step.
  void Measured(double per_step) {
    if (!(per_step > 0)) return;
    cheapest_ = cheapest_ > 0 ? std::min(cheapest_, per_step) : per_step;
    seconds_ =
        seconds_ > 0 ? 0.8 * seconds_ + 0.2 * std::min(per_step, kOutlier * seconds_) : per_step;
  }
  double seconds() const { return seconds_; }

 private:
  double seconds_ = 0;   // per step (0: not measured yet)
  double cheapest_ = 0;  // the cheapest step measured
};

}  // namespace urlab::net
