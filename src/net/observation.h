#pragma once
// The observation map of protocol.md (step_ok, reset_ok, state/full): time, step, sim and wall
// time, and per articulation qpos and qvel (minimal), plus ctrl, act and sensors by name
// (standard), plus body poses and actuator forces (full). Built from a state frame, never from
// live mjData. Thread: any (pure).
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "net/topic_table.h"
#include "urlab/physics/state_frame.h"

namespace urlab::net {

using Json = nlohmann::ordered_json;

// {"sec", "nsec"} of a time in seconds.
Json TimeOf(double seconds);
// A numeric vector: a list of numbers, or packed little-endian f64 bytes when `binary`.
Json Array(const double* v, std::size_t n, bool binary);
// True for "minimal", "standard" and "full".
bool IsObservationLevel(const std::string& level);
Json Observation(const std::vector<ArticulationTopics>& tables, const physics::StateFrame& f,
                 const std::string& level, bool binary);

}  // namespace urlab::net
