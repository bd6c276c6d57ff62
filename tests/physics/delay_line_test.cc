// The delay line behind emulated latency: a value pushed at tick t comes out exactly `delay`
// ticks later; jitter is uniform on -J..+J for a seed (same seed, same draws) and never
// reorders; the rate cap holds the output between updates; Restart repeats the sequence; the
// latency policy resolves seconds and rates to steps.
#include "urlab/physics/delay_line.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "urlab/physics/latency.h"

namespace urlab::physics {
namespace {

// The value pushed at tick t is t; returns the output per tick.
std::vector<int> RunLine(DelayLine<int>& line, int ticks) {
  std::vector<int> out;
  for (int t = 0; t < ticks; ++t) out.push_back(line.Push(t));
  return out;
}

TEST(DelayLineTest, ExactDelayInTicks) {
  for (int k : {0, 1, 3, 10}) {
    DelayLine<int> line(DelaySpec{k, 0, 0, 1});
    const std::vector<int> out = RunLine(line, 50);
    for (int t = 0; t < 50; ++t) {
      // Before the first release the line holds the first value (0).
      EXPECT_EQ(out[static_cast<std::size_t>(t)], t >= k ? t - k : 0) << "k=" << k << " t=" << t;
    }
  }
}

TEST(DelayLineTest, JitterStaysWithinItsBoundsAndNeverReorders) {
  DelayLine<int> line(DelaySpec{4, 2, 0, 99});
  int last = 0;
  std::map<int, int> lags;
  for (int t = 0; t < 5000; ++t) {
    const int out = line.Push(t);
    EXPECT_GE(out, last) << "t=" << t;  // never older than what was already shown
    last = out;
    if (t >= 10) {
      const int lag = t - out;
      // A value released on time has lag delay + J in 2..6; a tick where nothing new was
      // released shows the previous value, one tick older each time, but never beyond the
      // largest delay (6) since every value is out by then.
      EXPECT_GE(lag, 2);
      EXPECT_LE(lag, 6);
      ++lags[lag];
    }
  }
  for (int lag = 2; lag <= 6; ++lag) EXPECT_GT(lags[lag], 0) << "lag " << lag << " never seen";
}

TEST(DelayLineTest, JitterDrawsAreUniformOnTheIntegersForASeed) {
  constexpr int kJ = 3;
  constexpr int kN = 70000;
  DelayLine<int> line(DelaySpec{5, kJ, 0, 12345});
  std::map<int, int> counts;
  for (int t = 0; t < kN; ++t) {
    line.Push(t);
    ++counts[line.last_jitter()];
  }
  ASSERT_EQ(counts.size(), 2u * kJ + 1);
  EXPECT_EQ(counts.begin()->first, -kJ);
  EXPECT_EQ(counts.rbegin()->first, kJ);
  // Chi-square against the uniform distribution, 6 degrees of freedom: 22.46 is the 0.999
  // quantile (a fixed seed, so this is a fixed number, far from the bound when uniform).
  const double expected = static_cast<double>(kN) / (2 * kJ + 1);
  double chi2 = 0;
  for (const auto& [j, c] : counts) chi2 += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi2, 22.46);
}

TEST(DelayLineTest, SameSeedSameDelaysAndRestartRepeatsThem) {
  DelayLine<int> a(DelaySpec{3, 2, 0, 7});
  DelayLine<int> b(DelaySpec{3, 2, 0, 7});
  DelayLine<int> c(DelaySpec{3, 2, 0, 8});
  const std::vector<int> ra = RunLine(a, 300);
  EXPECT_EQ(ra, RunLine(b, 300));
  EXPECT_NE(ra, RunLine(c, 300));
  a.Restart();
  EXPECT_EQ(ra, RunLine(a, 300));
}

TEST(DelayLineTest, RateCapHoldsTheLastValueBetweenUpdates) {
  DelayLine<int> line(DelaySpec{2, 0, 5, 1});
  const std::vector<int> out = RunLine(line, 60);
  int changes = 0;
  for (std::size_t t = 1; t < out.size(); ++t) {
    if (out[t] != out[t - 1]) {
      ++changes;
      EXPECT_EQ(out[t], static_cast<int>(t) - 2);  // the newest released value
    }
  }
  // One change every 5 ticks at most.
  EXPECT_LE(changes, 12);
  EXPECT_GE(changes, 10);
  for (std::size_t t = 5; t < out.size(); ++t) {
    EXPECT_LE(static_cast<int>(t) - out[t], 2 + 4) << t;  // held at most min_interval - 1 more
  }
}

TEST(LatencyPolicyTest, SecondsAndRatesResolveToSteps) {
  LatencySetting s;
  ASSERT_EQ(SetLatencyKey(&s, "delay", 0.0105), "");
  ASSERT_EQ(SetLatencyKey(&s, "jitter_steps", 2), "");
  ASSERT_EQ(SetLatencyKey(&s, "rate_hz", 30), "");
  const DelaySpec spec = ResolveLatency(s, 0.002, 5);
  EXPECT_EQ(spec.delay, 5);  // round(0.0105 / 0.002)
  EXPECT_EQ(spec.jitter, 2);
  EXPECT_EQ(spec.min_interval, 17);  // ceil(1 / (30 * 0.002)) = ceil(16.67)
  EXPECT_EQ(spec.seed, 5u);
  EXPECT_NE(SetLatencyKey(&s, "delay_steps", 1.5), "");
  EXPECT_NE(SetLatencyKey(&s, "delay", -1), "");
  EXPECT_NE(SetLatencyKey(&s, "delay", NAN), "");
  EXPECT_NE(SetLatencyKey(&s, "lag", 1), "");
  EXPECT_NE(LatencySeed(1, 0, LatencyChannel::kControl),
            LatencySeed(1, 0, LatencyChannel::kObservation));
  EXPECT_NE(LatencySeed(1, 0, LatencyChannel::kControl),
            LatencySeed(1, 1, LatencyChannel::kControl));
}

}  // namespace
}  // namespace urlab::physics
