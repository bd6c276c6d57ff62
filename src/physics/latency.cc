#include "urlab/physics/latency.h"

#include <cmath>

namespace urlab::physics {

namespace {

// The key table: each key, what it sets.
struct KeyRow {
  std::string_view key;
  double LatencySetting::*field;
  bool LatencySetting::*in_steps;  // nullptr: rate_hz
  bool steps;                      // the value counts steps
};
constexpr KeyRow kKeys[] = {
    {"delay_steps", &LatencySetting::delay, &LatencySetting::delay_in_steps, true},
    {"delay", &LatencySetting::delay, &LatencySetting::delay_in_steps, false},
    {"jitter_steps", &LatencySetting::jitter, &LatencySetting::jitter_in_steps, true},
    {"jitter", &LatencySetting::jitter, &LatencySetting::jitter_in_steps, false},
    {"rate_hz", &LatencySetting::rate_hz, nullptr, false},
};

int ToSteps(double value, bool in_steps, double timestep) {
  if (in_steps) return static_cast<int>(value);
  if (timestep <= 0) return 0;
  return static_cast<int>(std::llround(value / timestep));
}

}  // namespace

const std::vector<std::string_view>& LatencyKeys() {
  static const std::vector<std::string_view> keys = [] {
    std::vector<std::string_view> k;
    for (const KeyRow& r : kKeys) k.push_back(r.key);
    return k;
  }();
  return keys;
}

std::string SetLatencyKey(LatencySetting* setting, std::string_view key, double value) {
  for (const KeyRow& r : kKeys) {
    if (r.key != key) continue;
    if (!std::isfinite(value) || value < 0) {
      return "'" + std::string(key) + "' must be a finite number >= 0";
    }
    if (r.steps && (value != std::floor(value) || value > 1e6)) {
      return "'" + std::string(key) + "' must be a whole number of steps (at most 1000000)";
    }
    if (!r.steps && r.in_steps && value > 60) {
      return "'" + std::string(key) + "' must be at most 60 seconds";
    }
    setting->*r.field = value;
    if (r.in_steps) setting->*r.in_steps = r.steps;
    return "";
  }
  std::string known;
  for (const KeyRow& r : kKeys) known += (known.empty() ? "" : ", ") + std::string(r.key);
  return "unknown latency key '" + std::string(key) + "' (known: " + known + ")";
}

std::map<std::string, double> LatencyFields(const LatencySetting& s) {
  std::map<std::string, double> out;
  out[s.delay_in_steps ? "delay_steps" : "delay"] = s.delay;
  out[s.jitter_in_steps ? "jitter_steps" : "jitter"] = s.jitter;
  out["rate_hz"] = s.rate_hz;
  return out;
}

DelaySpec ResolveLatency(const LatencySetting& s, double timestep, std::uint64_t seed) {
  DelaySpec spec;
  spec.delay = ToSteps(s.delay, s.delay_in_steps, timestep);
  spec.jitter = ToSteps(s.jitter, s.jitter_in_steps, timestep);
  if (s.rate_hz > 0 && timestep > 0) {
    spec.min_interval = static_cast<int>(std::ceil(1.0 / (s.rate_hz * timestep) - 1e-9));
  }
  spec.seed = seed;
  return spec;
}

std::uint64_t LatencySeed(std::uint64_t seed, std::size_t index, LatencyChannel channel) {
  return DeriveSeed(seed,
                    static_cast<std::uint64_t>(index) * 4 + static_cast<std::uint64_t>(channel));
}

}  // namespace urlab::physics
