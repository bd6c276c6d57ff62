#include "core/spin_wait.h"

#include <gtest/gtest.h>

#include <thread>

namespace urlab {
namespace {

using namespace std::chrono_literals;
using Clock = SpinWait::Clock;

TEST(SpinWaitTest, ReturnsAsSoonAsDoneOrWhenTheLimitPasses) {
  // A loaded machine may preempt this thread mid-spin (which the SpinWait then reports as a
  // back-off); such attempts do not count, and a few tries find an undisturbed one.
  for (int attempt = 0; attempt < 20; ++attempt) {
    SpinWait spin;
    int calls = 0;
    const bool done = spin.Spin(1s, [&] { return ++calls == 3; });
    const auto t0 = Clock::now();
    const bool timed_out = !spin.Spin(2ms, [] { return false; });
    const auto took = Clock::now() - t0;
    if (spin.backoffs() > 0) continue;
    EXPECT_TRUE(done);
    EXPECT_EQ(calls, 3);
    EXPECT_TRUE(timed_out);
    EXPECT_GE(took, 2ms);
    return;
  }
  GTEST_SKIP() << "this thread was preempted in every attempt (a loaded machine)";
}

// A turn that lasts longer than a core's fair share means the spinner was preempted: it stops,
// and the next waits within the back-off only look once instead of spinning.
TEST(SpinWaitTest, GivesUpAndBacksOffWhenATurnWasPreempted) {
  SpinWait spin;
  int calls = 0;
  const auto t0 = Clock::now();
  EXPECT_FALSE(spin.Spin(1s, [&] {
    if (++calls == 2) std::this_thread::sleep_for(2 * SpinWait::kPreemptedTurn);  // "preempted"
    return false;
  }));
  EXPECT_LT(Clock::now() - t0, 500ms);  // did not spin on to the limit
  EXPECT_EQ(spin.backoffs(), 1u);
  calls = 0;
  const auto t1 = Clock::now();
  const bool spun = spin.Spin(1s, [&] { return ++calls > 1000; });
  if (Clock::now() - t1 < SpinWait::kBackoff / 2) {  // surely still within the back-off
    EXPECT_FALSE(spun);
    EXPECT_EQ(calls, 1);
  }
  std::this_thread::sleep_for(SpinWait::kBackoff);
  calls = 0;
  const bool again = spin.Spin(1s, [&] { return ++calls == 50; });  // spinning again
  if (spin.backoffs() == 1) {                                       // (unless preempted once more)
    EXPECT_TRUE(again);
    EXPECT_EQ(calls, 50);
  }
}

}  // namespace
}  // namespace urlab
