#include "world/realtime_watch.h"

#include <fmt/format.h>

#include <algorithm>

namespace urlab::world {

std::optional<std::string> RealTimeWatch::Update(Clock::time_point now, double rtf, double target,
                                                 bool paced) {
  if (!paced || !(target > 0) || rtf >= kBehind * target) {
    behind_since_.reset();
    last_warning_.reset();
    return std::nullopt;
  }
  if (!behind_since_) {
    behind_since_ = now;
    lowest_ = rtf;
  }
  lowest_ = std::min(lowest_, rtf);
  if (now - *behind_since_ < kAfter) return std::nullopt;
  if (last_warning_ && now - *last_warning_ < kPeriod) return std::nullopt;
  last_warning_ = now;
  const double seconds = std::chrono::duration<double>(now - *behind_since_).count();
  return fmt::format(
      "the simulation runs at {:.2f}x real time (asked for {:.2f}x; as low as {:.2f}x) for "
      "{:.0f} s: this machine cannot keep up with the model's timestep. A larger timestep, "
      "fewer contacts or --speed below 100 make it keep pace (warned again every {} s while "
      "behind)",
      rtf, target, lowest_, seconds,
      std::chrono::duration_cast<std::chrono::seconds>(kPeriod).count());
}

}  // namespace urlab::world
