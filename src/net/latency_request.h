#pragma once
// One emulated-latency setting read from a step-server request map (set_latency's channels,
// set_camera_delay's cameras): the keys of physics/latency.h (delay_steps or delay, jitter_steps
// or jitter, rate_hz) and the seconds-and-rate names other clients use (delay_s, jitter_s,
// max_fps; clock "sim"). Refusals are bad_value naming the field. Thread: any (pure).
#include <cstdint>
#include <optional>
#include <string>

#include "net/msgpack_codec.h"
#include "urlab/physics/latency.h"

namespace urlab::net {

// `what` names the map in messages. With `seed` given, the map may also carry `seed` (a whole
// number >= 0), stored there; without, `seed` is refused like any unknown key.
physics::LatencySetting LatencySettingFromRequest(const Json& v, const std::string& what,
                                                  std::optional<std::uint64_t>* seed = nullptr);

// A whole number >= 0 (a seed), else bad_value naming `what`.
std::uint64_t SeedFromRequest(const Json& v, const std::string& what);

}  // namespace urlab::net
