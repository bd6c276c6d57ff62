#pragma once
// When a paced run cannot keep up with its target speed: fed the engine's measured real-time
// factor (PhysicsEngine::real_time_factor, averaged over its measurement window) on every tick,
// it says when to warn: after the factor stayed below kBehind of the target for kAfter, then at
// most once per kPeriod while it stays behind (a long slow run gets a reminder, never a flood).
// A paused engine, one running as fast as possible or a recovery resets it. Thread: one owner
// (the CLI's main thread); plain data.
#include <chrono>
#include <optional>
#include <string>

namespace urlab::world {

class RealTimeWatch {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr double kBehind = 0.95;
  static constexpr Clock::duration kAfter = std::chrono::seconds(3);
  static constexpr Clock::duration kPeriod = std::chrono::seconds(30);

  // `rtf`: measured simulated seconds per wall second; `target`: the speed asked for (1 at
  // 100 %). Returns the warning to log now, if any.
  std::optional<std::string> Update(Clock::time_point now, double rtf, double target, bool paced);

 private:
  std::optional<Clock::time_point> behind_since_;
  std::optional<Clock::time_point> last_warning_;
  double lowest_ = 0;
};

}  // namespace urlab::world
