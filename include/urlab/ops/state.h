#pragma once
// State edits: an articulation's joint positions, a mocap body's pose, the physics options. One
// typed function per operation with one validation (ops::OpError with the wire code, nothing
// applied), called alike by the step server (set_qpos, set_mocap_pose, read_mocap_pose,
// set_sim_options) and the viewer's panel (its physics options).
//
// Thread: any (each queues one engine command and returns its sequence number).
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/ops/error.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// `qpos`: every joint of the articulation in joint order, or 7 values for its free base alone.
// no_joints, dim_mismatch, bad_value (a value out of range, a quaternion whose norm is not ~1).
std::uint64_t SetQpos(world::Session& session, std::string_view articulation,
                      const std::vector<double>& qpos);

// The mocap index of body `body` (full name, with its prefix): unknown_body, not_mocap_body.
int MocapIndex(const world::Session& session, std::string_view body);
// Sets a mocap body's pose (MuJoCo frame: metres, quaternion w x y z); a position out of range
// or a quaternion whose norm is not ~1 is bad_value.
std::uint64_t SetMocapPose(world::Session& session, std::string_view body,
                           const std::array<double, 3>& pos, const std::array<double, 4>& quat);

// Physics options to change (absent: unchanged). Each number within its range
// (ops/value_ranges.h), integrator/cone/solver as MuJoCo's enum values.
struct OptionsChange {
  std::optional<double> timestep, impratio, tolerance, density, viscosity;
  std::optional<std::array<double, 3>> gravity, wind, magnetic;
  std::optional<int> iterations, integrator, cone, solver;
};
// "Euler", "RK4", "implicit"; "pyramidal", "elliptic"; "PGS", "CG", "Newton".
const std::vector<const char*>& IntegratorNames();
const std::vector<const char*>& ConeNames();
const std::vector<const char*>& SolverNames();
// Writes `change` into `o` (no checks: SetOptions checked it).
void ApplyOptions(const OptionsChange& change, mjOption& o);
struct OptionsSet {
  std::uint64_t seq = 0;
  std::shared_ptr<mjOption> options;  // every option once the command applied
};
OptionsSet SetOptions(world::Session& session, const OptionsChange& change);

}  // namespace urlab::ops
