#pragma once
// The observation map of docs/protocol.md (step_ok, reset_ok, state/full): time, step, sim and wall
// time, frame_id, paused, and per articulation qpos and qvel (minimal), plus ctrl, act and sensors
// by name (standard), plus body poses and actuator forces (full). Built from a state frame, never
// from live mjData. One layout, written either straight into msgpack bytes (the hot path: every
// lockstep reply and every state/full message) or into a JSON tree (JSON clients).
// Thread: any (pure).
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "net/free_bodies.h"
#include "net/msgpack_codec.h"
#include "net/topic_table.h"
#include "urlab/physics/state_frame.h"

namespace urlab::net {

enum class ObsLevel { kMinimal, kStandard, kFull };

// "minimal", "standard" or "full"; nothing for anything else.
std::optional<ObsLevel> ParseObservationLevel(std::string_view level);

// A numeric vector: a list of numbers, or packed little-endian f64 bytes when `binary`.
Json Array(const double* v, std::size_t n, bool binary);

// The keys the per-articulation data travels under: ours (`per_articulation`, `entities`), the
// 2026 dialect's (`arts`, `scene`, and at level full each articulation's bodies as
// `bodies {name: {xpos, xquat}}` in place of the `xpos`/`xquat` maps), or both (the state/full
// snapshot while a 2026 client is connected; docs/protocol.md, "The 2026 dialect").
enum class ObsKeys { kOurs, k2026, kBoth };

// The observation's top-level entries (time, step, sim_time, wall_time, paused, frame_id, then
// per_articulation and entities and/or arts and scene), to be written inside a map the caller
// opened; ObservationEntries says how many. `entities` and `scene` map each of `free_bodies`
// (net/free_bodies.h; none when null) to its free joint's {qpos [7], qvel [6]}.
inline constexpr std::size_t kObservationEntries = 8;
constexpr std::size_t ObservationEntries(ObsKeys keys) {
  return keys == ObsKeys::kBoth ? kObservationEntries + 2 : kObservationEntries;
}
void WriteObservationEntries(MsgpackWriter& out, const std::vector<ArticulationTopics>& tables,
                             const physics::StateFrame& f, ObsLevel level, bool binary,
                             ObsKeys keys = ObsKeys::kOurs,
                             const std::vector<FreeBodyEntry>* free_bodies = nullptr);
// Adds the same entries to the JSON object *reply.
void AddObservation(Json* reply, const std::vector<ArticulationTopics>& tables,
                    const physics::StateFrame& f, ObsLevel level, bool binary,
                    ObsKeys keys = ObsKeys::kOurs,
                    const std::vector<FreeBodyEntry>* free_bodies = nullptr);
// The observation alone, as a JSON tree.
Json Observation(const std::vector<ArticulationTopics>& tables, const physics::StateFrame& f,
                 ObsLevel level, bool binary, ObsKeys keys = ObsKeys::kOurs,
                 const std::vector<FreeBodyEntry>* free_bodies = nullptr);

}  // namespace urlab::net
