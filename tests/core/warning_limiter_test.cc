// Repeated MuJoCo warnings are logged at most once a second per kind, with counts; captures
// (the test fixture) still see every one.
#include "core/warning_limiter.h"

#include <gtest/gtest.h>

#include "urlab/core/mujoco_handlers.h"

namespace urlab {
namespace {

using internal::WarningLimiter;
using namespace std::chrono_literals;

TEST(WarningLimiterTest, KindsIgnoreNumbers) {
  EXPECT_EQ(WarningLimiter::KindOf("Nan, Inf or huge value in QACC at DOF 12. Time = 0.1230."),
            WarningLimiter::KindOf("Nan, Inf or huge value in QACC at DOF 3. Time = 99.5."));
  EXPECT_NE(WarningLimiter::KindOf("contact buffer is full"),
            WarningLimiter::KindOf("constraint buffer is full"));
}

TEST(WarningLimiterTest, OnePerSecondPerKindWithTheCountLeftOut) {
  WarningLimiter limiter(1s);
  const auto t0 = WarningLimiter::Clock::time_point{} + 100s;
  std::uint64_t skipped = 99;
  EXPECT_TRUE(limiter.Admit("QACC at DOF 1. Time = 0.001.", t0, &skipped));
  EXPECT_EQ(skipped, 0u);
  int logged = 0;
  // 78,000 warnings in 3 s (what a bad model produced): 3 lines of this kind, not 78,000.
  for (int i = 1; i < 78000; ++i) {
    const auto t = t0 + std::chrono::microseconds(i * 38);
    std::uint64_t s = 0;
    if (limiter.Admit(
            "QACC at DOF " + std::to_string(i % 7) + ". Time = 0." + std::to_string(i) + ".", t,
            &s)) {
      ++logged;
      EXPECT_GT(s, 1000u);
    }
  }
  EXPECT_EQ(logged, 2);
  // Another kind is not held back by the first.
  EXPECT_TRUE(limiter.Admit("contact buffer is full", t0 + 1ms, &skipped));
  const auto left = limiter.TakeSkipped();
  ASSERT_EQ(left.size(), 1u);
  EXPECT_GT(left[0].second, 0u);
  EXPECT_TRUE(limiter.TakeSkipped().empty());
}

TEST(WarningLimiterTest, CapturesStillSeeEveryWarning) {
  WarningCapture capture;
  for (int i = 0; i < 5000; ++i) ReportMujocoWarning("Test warning " + std::to_string(i));
  EXPECT_EQ(capture.Take().size(), 5000u);
  FlushMujocoWarningCounts();
}

}  // namespace
}  // namespace urlab
