// The event log: each kind of engine event is logged at most once per interval, with the number
// held back reported on the next line of that kind (injectable clock: no sleeping).
#include "urlab/world/event_log.h"

#include <gtest/gtest.h>

namespace urlab::world {
namespace {

using physics::EngineEvent;
using physics::EngineEventKind;

TEST(EventLogTest, RepeatedEventsAreRateLimitedPerKindWithCounts) {
  EventLog::Clock::time_point now{};
  EventLog log(std::chrono::seconds(1), [&] { return now; });
  EngineEvent divergence{EngineEventKind::kDivergence, 0.1, "simulation diverged: bad qacc"};
  EngineEvent reset{EngineEventKind::kReset, 0.1, "reset after divergence"};
  // A model blowing up 5000 times a second under auto-reset: two kinds, one line each.
  for (int i = 0; i < 5000; ++i) {
    log.OnEvent(divergence);
    log.OnEvent(reset);
    now += std::chrono::microseconds(150);
  }
  EXPECT_EQ(log.lines(), 2);
  EXPECT_EQ(log.held_back_total(), 9998);
  now += std::chrono::seconds(1);
  log.OnEvent(divergence);  // logged, reporting the 4999 held back
  EXPECT_EQ(log.lines(), 3);
  log.Flush();  // the resets held back get one closing line
  EXPECT_EQ(log.lines(), 4);
  log.Flush();  // nothing more
  EXPECT_EQ(log.lines(), 4);
  // Errors are a kind of their own: not held back by the others.
  log.OnEvent({EngineEventKind::kError, 0.2, "MuJoCo error"});
  EXPECT_EQ(log.lines(), 5);
}

}  // namespace
}  // namespace urlab::world
