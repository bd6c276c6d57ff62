#pragma once
// Latency policy: what a `latency:` entry (scene file or the step server's set_latency) means, and
// how it resolves to the ticks of a DelayLine (physics/delay_line.h, the mechanism).
//
// One setting per channel (control, observation):
//   delay_steps: N  or  delay: SECONDS    the value takes effect N steps (round(SECONDS / dt))
//                                         after it arrives
//   jitter_steps: J or  jitter: SECONDS   each value's delay is delay + U, U uniform on the
//                                         integers -J..+J (seconds rounded to steps), drawn from
//                                         the seed; never below 0 and never reordering (a value
//                                         that would overtake an older one waits for it)
//   rate_hz: R                            the receiver sees at most R updates per second: the
//                                         output changes at most every ceil(1 / (R dt)) steps,
//                                         holding the last value in between (0: no cap)
// Thread: any (pure).
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/delay_line.h"

namespace urlab::physics {

struct LatencySetting {
  double delay = 0;  // steps when delay_in_steps, else seconds
  bool delay_in_steps = true;
  double jitter = 0;  // steps when jitter_in_steps, else seconds
  bool jitter_in_steps = true;
  double rate_hz = 0;  // 0: no rate cap
  bool operator==(const LatencySetting&) const = default;
  bool empty() const { return delay == 0 && jitter == 0 && rate_hz == 0; }
};

// The keys of one setting, in the order the docs list them.
const std::vector<std::string_view>& LatencyKeys();
// Sets `key` of *setting to `value`; returns an error message ("" when accepted): unknown key,
// negative or non-finite value, a step count that is not a whole number.
std::string SetLatencyKey(LatencySetting* setting, std::string_view key, double value);
// The setting as the keys it was given with (for replies): {"delay_steps": 3, ...}.
std::map<std::string, double> LatencyFields(const LatencySetting& setting);

// A delay line holds up to delay + jitter + the rate cap's interval values: at most this many
// steps in all (a setting beyond it is refused where it meets a timestep: the compiled scene's
// checks and set_latency).
inline constexpr int kMaxLatencySteps = 1000000;
// "" when the setting resolves to at most kMaxLatencySteps steps at `timestep`, else the
// problem, naming the fields and the limit.
std::string CheckLatency(const LatencySetting& setting, double timestep);

// Resolves a setting for a model stepping at `timestep` seconds. Each count saturates at
// kMaxLatencySteps (never an int overflow, whatever the caller checked).
DelaySpec ResolveLatency(const LatencySetting& setting, double timestep, std::uint64_t seed);

// The channels of one articulation.
enum class LatencyChannel : std::uint64_t { kControl = 0, kObservation = 1 };
// The seed of a channel of articulation `index` from the run's seed: every channel draws its own
// jitter, the same for the same seed.
std::uint64_t LatencySeed(std::uint64_t seed, std::size_t index, LatencyChannel channel);

// An articulation's latency: control and observation.
struct ArticulationLatency {
  LatencySetting control;
  LatencySetting observation;
  bool operator==(const ArticulationLatency&) const = default;
};

}  // namespace urlab::physics
