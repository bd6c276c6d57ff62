// The injectable clock: a ManualClock moves only when told, and a thread sleeping on it wakes
// exactly when its deadline is reached.
#include "urlab/core/clock.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

namespace urlab {
namespace {

using namespace std::chrono_literals;

TEST(ClockTest, ManualClockMovesOnlyWhenTold) {
  ManualClock clock;
  const Clock::time_point t0 = clock.now();
  EXPECT_EQ(clock.now(), t0);
  clock.Advance(5ms);
  EXPECT_EQ(clock.now() - t0, 5ms);
  clock.Set(t0 + 1s);
  EXPECT_EQ(clock.now() - t0, 1s);
  clock.sleep_until(t0);  // a deadline already passed returns at once
  EXPECT_EQ(clock.sleep_calls(), 1u);
  EXPECT_EQ(clock.sleepers(), 0);
}

TEST(ClockTest, SleeperWakesWhenItsDeadlineIsReached) {
  ManualClock clock;
  const Clock::time_point deadline = clock.now() + 10ms;
  std::atomic<bool> woke{false};
  std::thread sleeper([&] {
    while (clock.now() < deadline) clock.sleep_until(deadline);  // may return early: re-check
    woke = true;
  });
  ASSERT_TRUE(clock.WaitForSleeper());
  clock.Advance(9ms);
  ASSERT_TRUE(clock.WaitForSleeper());  // still asleep: its deadline is 1 ms away
  EXPECT_FALSE(woke.load());
  clock.Advance(1ms);
  sleeper.join();
  EXPECT_TRUE(woke.load());
  EXPECT_EQ(clock.sleepers(), 0);
}

TEST(ClockTest, WaitForSleeperTimesOutWithoutOne) {
  ManualClock clock;
  EXPECT_FALSE(clock.WaitForSleeper(1, 1ms));
}

TEST(ClockTest, RealClockSleepsUntilTheDeadline) {
  Clock& clock = RealClock();
  const Clock::time_point deadline = clock.now() + 2ms;
  clock.sleep_until(deadline);
  EXPECT_GE(clock.now(), deadline);  // never early (how late is the machine's business)
}

}  // namespace
}  // namespace urlab
