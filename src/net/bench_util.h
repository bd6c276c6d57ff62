#pragma once
// Small helpers shared by the network benchmarks (latency_bench.cc, broadcast_bench.cc).
// Thread: any (pure).
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace urlab::net::bench {

template <typename... Args>
std::string Format(const char* fmt, Args... args) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, args...);
  return buf;
}

inline double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace urlab::net::bench
