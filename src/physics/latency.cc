#include "urlab/physics/latency.h"

#include <cmath>
#include <sstream>

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

// Steps as a double (not yet bounded).
double StepsOf(double value, bool in_steps, double timestep) {
  if (in_steps) return value;
  if (timestep <= 0) return 0;
  return std::round(value / timestep);
}
double IntervalOf(double rate_hz, double timestep) {
  if (!(rate_hz > 0) || !(timestep > 0)) return 0;
  return std::ceil(1.0 / (rate_hz * timestep) - 1e-9);
}
// A step count for a message: whole numbers as such, huge ones in exponent form.
std::string Count(double steps) {
  std::ostringstream o;
  if (steps < 1e15) {
    o << static_cast<long long>(steps);
  } else {
    o << steps;
  }
  return o.str();
}
int Saturate(double steps) {
  if (!(steps > 0)) return 0;
  return steps >= kMaxLatencySteps ? kMaxLatencySteps : static_cast<int>(steps);
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

std::string CheckLatency(const LatencySetting& s, double timestep) {
  const double delay = StepsOf(s.delay, s.delay_in_steps, timestep);
  const double jitter = StepsOf(s.jitter, s.jitter_in_steps, timestep);
  const double interval = IntervalOf(s.rate_hz, timestep);
  const double total = delay + jitter + (interval > 1 ? interval : 0);
  if (total <= kMaxLatencySteps) return "";
  std::ostringstream m;
  m << "delay + jitter + the rate_hz interval come to " << Count(total) << " steps at timestep "
    << timestep << " s (";
  const char* sep = "";
  if (delay > 0) {
    m << sep << (s.delay_in_steps ? "delay_steps " : "delay ") << s.delay << ": " << Count(delay);
    sep = ", ";
  }
  if (jitter > 0) {
    m << sep << (s.jitter_in_steps ? "jitter_steps " : "jitter ") << s.jitter << ": "
      << Count(jitter);
    sep = ", ";
  }
  if (interval > 1) m << sep << "rate_hz " << s.rate_hz << ": one value every " << Count(interval);
  m << "); at most " << kMaxLatencySteps << " steps";
  return m.str();
}

DelaySpec ResolveLatency(const LatencySetting& s, double timestep, std::uint64_t seed) {
  DelaySpec spec;
  spec.delay = Saturate(StepsOf(s.delay, s.delay_in_steps, timestep));
  spec.jitter = Saturate(StepsOf(s.jitter, s.jitter_in_steps, timestep));
  spec.min_interval = Saturate(IntervalOf(s.rate_hz, timestep));
  spec.seed = seed;
  return spec;
}

std::uint64_t LatencySeed(std::uint64_t seed, std::size_t index, LatencyChannel channel) {
  return DeriveSeed(seed,
                    static_cast<std::uint64_t>(index) * 4 + static_cast<std::uint64_t>(channel));
}

}  // namespace urlab::physics
