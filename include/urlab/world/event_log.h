#pragma once
// EventLog: writes engine events to the log without flooding it. Each kind of event (reset,
// restore, divergence, error) is logged at most once per interval; the ones held back are counted
// and the count is reported with the next line of that kind (and by Flush at the end). A model
// that keeps blowing up under auto-reset logs about two lines a second, not tens of thousands.
//
// Threading: main thread only (it is an engine event listener, run inside Manager::Tick).
#include <array>
#include <chrono>
#include <functional>

#include "urlab/physics/engine.h"

namespace urlab::world {

class EventLog {
 public:
  using Clock = std::chrono::steady_clock;
  // `now` is injectable for tests.
  explicit EventLog(Clock::duration interval = std::chrono::seconds(1),
                    std::function<Clock::time_point()> now = Clock::now);

  // Logs `e` (or counts it when its kind was logged less than an interval ago).
  void OnEvent(const physics::EngineEvent& e);
  // Logs how many events of each kind were held back since their last line.
  void Flush();

  // Lines written and events held back so far (for tests and summaries).
  int lines() const { return lines_; }
  long held_back_total() const { return held_back_total_; }

 private:
  struct PerKind {
    Clock::time_point last{};
    bool logged = false;
    long held_back = 0;
  };
  Clock::duration interval_;
  std::function<Clock::time_point()> now_;
  std::array<PerKind, 4> kinds_{};
  int lines_ = 0;
  long held_back_total_ = 0;
};

}  // namespace urlab::world
