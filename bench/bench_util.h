#pragma once
// Timing helpers shared by the benchmarks: every benchmark compares against a baseline measured
// in the same process, with interleaved runs and medians.
#include <algorithm>
#include <chrono>
#include <vector>

namespace urlab::bench {

inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Wall-clock seconds taken by f().
template <typename F>
double Seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace urlab::bench
