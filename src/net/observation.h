#pragma once
// The observation map of docs/protocol.md (step_ok, reset_ok, state/full): time, step, sim and wall
// time, paused, and per articulation qpos and qvel (minimal), plus ctrl, act and sensors by name
// (standard), plus body poses and actuator forces (full). Built from a state frame, never from
// live mjData. One layout, written either straight into msgpack bytes (the hot path: every
// lockstep reply and every state/full message) or into a JSON tree (JSON clients).
// Thread: any (pure).
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "net/msgpack_codec.h"
#include "net/topic_table.h"
#include "urlab/physics/state_frame.h"

namespace urlab::net {

enum class ObsLevel { kMinimal, kStandard, kFull };

// "minimal", "standard" or "full"; nothing for anything else.
std::optional<ObsLevel> ParseObservationLevel(std::string_view level);

// A numeric vector: a list of numbers, or packed little-endian f64 bytes when `binary`.
Json Array(const double* v, std::size_t n, bool binary);

// The observation's top-level entries (time, step, sim_time, wall_time, paused,
// per_articulation, entities), to be written inside a map the caller opened.
inline constexpr std::size_t kObservationEntries = 7;
void WriteObservationEntries(MsgpackWriter& out, const std::vector<ArticulationTopics>& tables,
                             const physics::StateFrame& f, ObsLevel level, bool binary);
// Adds the same entries to the JSON object *reply.
void AddObservation(Json* reply, const std::vector<ArticulationTopics>& tables,
                    const physics::StateFrame& f, ObsLevel level, bool binary);
// The observation alone, as a JSON tree.
Json Observation(const std::vector<ArticulationTopics>& tables, const physics::StateFrame& f,
                 ObsLevel level, bool binary);

}  // namespace urlab::net
