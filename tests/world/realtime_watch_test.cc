// The real-time warning's policy: only after the factor stayed behind for a while, then once per
// period while it stays behind; never while paused or running as fast as possible.
#include "world/realtime_watch.h"

#include <gtest/gtest.h>

namespace urlab {
namespace {

using world::RealTimeWatch;
using namespace std::chrono_literals;

// Feeds `rtf` every 16 ms for `span` from `*t`; returns the warnings given.
int Feed(RealTimeWatch& w, RealTimeWatch::Clock::time_point* t, std::chrono::milliseconds span,
         double rtf, double target = 1.0, bool paced = true) {
  int warnings = 0;
  for (const auto end = *t + span; *t < end; *t += 16ms) {
    if (w.Update(*t, rtf, target, paced)) ++warnings;
  }
  return warnings;
}

TEST(RealTimeWatch, WarnsAfterAFewSecondsBehindThenOncePerPeriod) {
  RealTimeWatch w;
  auto t = RealTimeWatch::Clock::time_point{} + 100s;
  EXPECT_EQ(Feed(w, &t, 2900ms, 0.5), 0);  // not yet
  EXPECT_EQ(Feed(w, &t, 200ms, 0.5), 1);   // 3 s behind
  EXPECT_EQ(Feed(w, &t, 25s, 0.5), 0);     // no flood
  EXPECT_EQ(Feed(w, &t, 10s, 0.5), 1);     // the next period
  // Recovering resets it; a short dip does not warn.
  EXPECT_EQ(Feed(w, &t, 1s, 1.0), 0);
  EXPECT_EQ(Feed(w, &t, 2s, 0.9), 0);
  EXPECT_EQ(Feed(w, &t, 1s, 0.97), 0);  // within 95 %
  EXPECT_EQ(Feed(w, &t, 2s, 0.9), 0);
}

TEST(RealTimeWatch, TheTargetIsTheSpeedAskedForAndUnpacedRunsAreNeverBehind) {
  RealTimeWatch w;
  auto t = RealTimeWatch::Clock::time_point{} + 100s;
  EXPECT_EQ(Feed(w, &t, 10s, 0.5, /*target=*/0.5), 0);        // --speed 50 kept
  EXPECT_EQ(Feed(w, &t, 10s, 0.4, /*target=*/0.5), 1);        // --speed 50 not kept
  EXPECT_EQ(Feed(w, &t, 60s, 0.0, 1.0, /*paced=*/false), 0);  // paused or --max-speed
  const auto warning = [&] {
    RealTimeWatch v;
    auto u = t;
    std::optional<std::string> last;
    for (int i = 0; i < 400 && !last; ++i, u += 16ms) last = v.Update(u, 0.31, 1.0, true);
    return last.value_or("");
  }();
  EXPECT_NE(warning.find("0.31x real time (asked for 1.00x"), std::string::npos) << warning;
}

}  // namespace
}  // namespace urlab
