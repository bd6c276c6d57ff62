#include "net/latency_request.h"

#include "net/request_fields.h"

namespace urlab::net {

using request::Fail;

std::uint64_t SeedFromRequest(const Json& v, const std::string& what) {
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0)) {
    Fail("bad_value", what + " must be a whole number >= 0");
  }
  return v.get<std::uint64_t>();
}

physics::LatencySetting LatencySettingFromRequest(const Json& v, const std::string& what,
                                                  std::optional<std::uint64_t>* seed) {
  if (!v.is_object()) {
    Fail("bad_value",
         what + " must be a map (delay_steps or delay, jitter_steps or jitter, rate_hz)");
  }
  physics::LatencySetting s;
  bool delay = false, jitter = false;
  for (const auto& [key, value] : v.items()) {
    if (key == "seed" && seed) {
      *seed = SeedFromRequest(value, what + ".seed");
      continue;
    }
    if (key == "clock") {
      // Only simulated time: a delay counted on the wall clock would depend on the machine's
      // speed and load, so the same seed could not give the same run, nor a recording replay it.
      if (!value.is_string() || value.get<std::string>() != "sim") {
        const std::string given = value.is_string() ? "\"" + value.get<std::string>() + "\""
                                                    : std::string(value.type_name());
        Fail("bad_value",
             what + ".clock " + given +
                 ": only \"sim\" is served. Delays run on simulated time, so a lockstep run is "
                 "the same for the same seed and a recording replays it bit for bit; a "
                 "wall-clock delay would depend on the machine's speed and load. Leave clock "
                 "out (or give \"sim\") and give the delay in simulated seconds (delay_s, "
                 "jitter_s) or in physics steps (delay_steps, jitter_steps)");
      }
      continue;
    }
    const std::string name = key == "delay_s"    ? "delay"
                             : key == "jitter_s" ? "jitter"
                             : key == "max_fps"  ? "rate_hz"
                                                 : key;
    const bool is_delay = name == "delay" || name == "delay_steps";
    const bool is_jitter = name == "jitter" || name == "jitter_steps";
    if ((is_delay && delay) || (is_jitter && jitter)) {
      Fail("bad_value", what + ": give the " + (is_delay ? "delay" : "jitter") +
                            " in steps or in seconds, not both");
    }
    delay |= is_delay;
    jitter |= is_jitter;
    if (!value.is_number()) Fail("bad_value", what + "." + key + " must be a number");
    const std::string problem = physics::SetLatencyKey(&s, name, value.get<double>());
    if (!problem.empty()) Fail("bad_value", what + ": " + problem);
  }
  return s;
}

}  // namespace urlab::net
