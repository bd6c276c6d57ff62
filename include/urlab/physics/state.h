#pragma once
// Full physics state capture and restore, through MuJoCo's mj_getState/mj_setState.
//
// A PhysicsState holds MuJoCo's integration state (mjSTATE_INTEGRATION) one component per array:
// time, qpos, qvel, act, the history buffers of delayed controls and sensors, qacc_warmstart (the
// constraint solver's warm start), ctrl, qfrc_applied, xfrc_applied, eq_active, mocap_pos,
// mocap_quat, userdata and the engine plugins' state. Everything else in mjData (kinematics,
// contacts, sensor data, energy, actuator forces) is recomputed from these by mj_forward, so
// RestoreState followed by stepping reproduces the original continuation bit for bit.
//
// The functions are pure and may be called from any thread, but the mjData passed in must not be
// stepped concurrently (see engine.h: use PhysicsEngine::Snapshot/Restore while it runs).
#include <mujoco/mujoco.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::physics {

// A state does not match a model, or serialised state bytes are corrupt. what() says which.
class StateError : public Error {
 public:
  using Error::Error;
};

// The model sizes a state was captured for; a state only applies to a model with equal sizes.
struct StateLayout {
  int nq = 0;
  int nv = 0;
  int na = 0;
  int nu = 0;
  int nbody = 0;
  int nmocap = 0;
  int nuserdata = 0;
  int nhistory = 0;      // mj_stateSize(m, mjSTATE_HISTORY)
  int neq = 0;           // eq_active entries
  int npluginstate = 0;  // plugin state entries

  // The layout of model `m`.
  static StateLayout Of(const mjModel* m);
  bool operator==(const StateLayout&) const = default;
  // "nq=.. nv=.. ..." for error messages.
  std::string str() const;
};

// A complete copy of the integration state of one mjData.
struct PhysicsState {
  StateLayout layout;
  double time = 0;
  std::vector<mjtNum> qpos;            // nq
  std::vector<mjtNum> qvel;            // nv
  std::vector<mjtNum> act;             // na
  std::vector<mjtNum> qacc_warmstart;  // nv
  std::vector<mjtNum> ctrl;            // nu
  std::vector<mjtNum> qfrc_applied;    // nv
  std::vector<mjtNum> xfrc_applied;    // 6 * nbody
  std::vector<mjtNum> mocap_pos;       // 3 * nmocap
  std::vector<mjtNum> mocap_quat;      // 4 * nmocap
  std::vector<mjtNum> userdata;        // nuserdata
  std::vector<mjtNum> history;         // nhistory
  std::vector<mjtNum> eq_active;       // neq (0 or 1)
  std::vector<mjtNum> plugin_state;    // npluginstate

  // True when both states hold exactly the same bits (NaNs compare equal to identical NaNs).
  bool BitwiseEquals(const PhysicsState& other) const;
  // True when the array sizes agree with `layout`.
  bool IsConsistent() const;
};

// Copies the state of `d` (any thread that owns `d`).
PhysicsState CaptureState(const mjModel* m, const mjData* d);

// Writes `state` into `d` without recomputing anything. Throws StateError when the state's
// layout does not match `m`. Prefer RestoreState.
void ApplyState(const mjModel* m, mjData* d, const PhysicsState& state);

// ApplyState, then mj_forward so that every derived quantity (poses, contacts, sensors) matches
// the state, then writes qpos and qacc_warmstart back: mj_forward normalises the quaternions in
// qpos in place and overwrites the warm start with the new qacc, either of which would make the
// next mj_step differ in the last bits from the original continuation. Throws StateError like
// ApplyState.
void RestoreState(const mjModel* m, mjData* d, const PhysicsState& state);

// Serialised format, little-endian: magic "URLS", u32 version, u32 header size, the layout
// (10 x i32), f64 time, u64 payload byte count, the arrays in PhysicsState's order as f64, then a
// u64 FNV-1a checksum of everything before it. Version 2 added history, eq_active and
// plugin_state (MuJoCo 3); version 1 is refused.
inline constexpr std::uint32_t kStateFormatVersion = 2;

// Serialises `state` to bytes. Throws StateError when the state is inconsistent.
std::vector<std::uint8_t> SerializeState(const PhysicsState& state);

// Parses bytes produced by SerializeState. Throws StateError with a specific message on a bad
// magic number, unsupported version, truncated or oversized input, size mismatch or checksum
// failure.
PhysicsState DeserializeState(std::span<const std::uint8_t> bytes);

}  // namespace urlab::physics
