// The shared-memory channel's wait policy (wire/shm_wait.h): how long a waiter spins before it
// sleeps, as a function of what it expects its partner to take and whether a core is free for the
// spinner; and what a client learns to expect from its round trips. Data only: no clock.
#include "wire/shm_wait.h"

#include <gtest/gtest.h>

#include <chrono>
#include <vector>

namespace urlab::wire {
namespace {

using std::chrono::microseconds;
using std::chrono::milliseconds;
using std::chrono::nanoseconds;

struct Row {
  nanoseconds expected;
  nanoseconds with_spare_core;     // SpinBudget when a core is free
  nanoseconds without_spare_core;  // ... and when every core is taken
  bool asks;                       // whether the policy asks about the cores at all
};

TEST(ShmWaitPolicy, SpinsAboutAsLongAsThePartnerIsExpectedToTakeThenSleeps) {
  const std::vector<Row> table = {
      // Nothing learnt yet: a short spin, then sleep.
      {nanoseconds(0), microseconds(30), microseconds(30), false},
      // Short waits (a raw ping-pong, one humanoid step): three times over, at least 30 us,
      // whatever the cores (cheaper than the wake-up it saves).
      {microseconds(5), microseconds(30), microseconds(30), false},
      {microseconds(46), microseconds(138), microseconds(138), false},
      {microseconds(100), microseconds(300), microseconds(300), false},
      // A window of 10 steps (~600 us): spun through on a free core (expected x 5/4 + 50 us);
      // without one (a driver gathering from two servers on two cores, a batch stepping on every
      // core) no spin: sleep at once.
      {microseconds(600), microseconds(800), nanoseconds(0), true},
      {milliseconds(1), microseconds(1300), nanoseconds(0), true},
      // Up to the cap of 3 ms.
      {microseconds(2500), milliseconds(3), nanoseconds(0), true},
      {milliseconds(3), milliseconds(3), nanoseconds(0), true},
      // Beyond it (a batch of environments): the wake-up is small beside the wait, and an idle
      // peer must not burn a core.
      {microseconds(3001), microseconds(30), microseconds(30), false},
      {milliseconds(40), microseconds(30), microseconds(30), false},
  };
  for (const Row& row : table) {
    SCOPED_TRACE(::testing::Message() << "expected " << row.expected.count() << " ns");
    int asked = 0;
    EXPECT_EQ(SpinBudget(row.expected,
                         [&] {
                           ++asked;
                           return true;
                         }),
              row.with_spare_core);
    EXPECT_EQ(SpinBudget(row.expected,
                         [&] {
                           ++asked;
                           return false;
                         }),
              row.without_spare_core);
    EXPECT_EQ(asked, row.asks ? 2 : 0);
  }
}

TEST(ShmWaitPolicy, AWaitUpToTheCapIsSpunThroughOnAFreeCoreAndNeverBeyondTheCap) {
  const auto yes = [] { return true; };
  const auto no = [] { return false; };
  for (nanoseconds e = microseconds(1); e <= ShmWait::kMaxSpin; e += microseconds(7)) {
    SCOPED_TRACE(::testing::Message() << "expected " << e.count() << " ns");
    EXPECT_GE(SpinBudget(e, yes), e);
    EXPECT_LE(SpinBudget(e, yes), ShmWait::kMaxSpin);
    // Without a free core a long wait is not spun for at all.
    if (e > ShmWait::kShortWait) {
      EXPECT_EQ(SpinBudget(e, no), nanoseconds(0));
    }
  }
}

TEST(ShmRoundTrips, LearnsTheTimePerStepAndTheOtherRequestsApart) {
  ShmRoundTrips r;
  EXPECT_EQ(r.Expected(1), nanoseconds(0));  // nothing learnt: SpinBudget's kMinSpin
  EXPECT_EQ(r.Expected(0), nanoseconds(0));
  r.Took(10, microseconds(600));
  EXPECT_EQ(r.Expected(10), microseconds(600));
  EXPECT_EQ(r.Expected(1), microseconds(60));
  EXPECT_EQ(r.Expected(100), microseconds(6000));
  EXPECT_EQ(r.Expected(0), nanoseconds(0));  // a request that does not step: not learnt yet
  r.Took(0, microseconds(8));
  EXPECT_EQ(r.Expected(0), microseconds(8));
  EXPECT_EQ(r.Expected(10), microseconds(600));  // unchanged by the other request
  // A changed cost is followed (a quarter of the way per round trip).
  r.Took(10, microseconds(1000));
  EXPECT_EQ(r.Expected(10), microseconds(700));
  for (int i = 0; i < 40; ++i) r.Took(10, microseconds(1000));
  EXPECT_NEAR(static_cast<double>(r.Expected(10).count()), 1e6, 1e3);
}

}  // namespace
}  // namespace urlab::wire
