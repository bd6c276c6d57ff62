// Simulation control (urlab/ops/simulation.h).
#include "urlab/ops/simulation.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>

#include "ops/value_ranges.h"
#include "urlab/ops/error.h"
#include "urlab/world/names.h"

namespace urlab::ops {

const world::Articulation& RequireArticulation(const world::Session& session,
                                               std::string_view name) {
  const world::Articulation* a = session.FindArticulation(name);
  if (!a) Fail("unknown_articulation", "no articulation '" + std::string(name) + "' in the scene");
  return *a;
}

namespace {

// The whole-model keyframe `name` (full or short name).
int FindKeyframe(const world::Session& session, const std::string& name) {
  std::vector<std::string> prefixes;
  for (const world::Articulation& a : session.articulations()) prefixes.push_back(a.prefix);
  int key = -1;
  try {
    key = world::FindNamed(session.engine().model(), mjOBJ_KEY, prefixes, name);
  } catch (const Error& e) {
    Fail("ambiguous_keyframe", e.what());
  }
  if (key < 0) Fail("unknown_keyframe", "no keyframe '" + name + "' (see list_keyframes)");
  return key;
}

// The joint values of `joints` as one state write, checked whole.
physics::cmd::SetState JointWrites(const world::Session& session,
                                   const std::vector<JointQpos>& joints, std::string_view what) {
  physics::cmd::SetState out;
  for (const JointQpos& jq : joints) {
    const world::Articulation& a = RequireArticulation(session, jq.articulation);
    const physics::JointView* found = a.bindings->joints().Find(jq.joint);
    if (!found) Fail("bad_value", a.name() + ": no joint '" + jq.joint + "'");
    const physics::JointView& j = *found;
    if (jq.qpos.size() != static_cast<std::size_t>(j.qpos_size)) {
      Fail("dim_mismatch", a.name() + ": joint '" + jq.joint + "' takes " +
                               std::to_string(j.qpos_size) + " qpos value(s), got " +
                               std::to_string(jq.qpos.size()));
    }
    CheckRanges(jq.qpos, "qpos", a.name() + ": joint '" + jq.joint + "'");
    out.qpos.push_back({j.qpos_adr, jq.qpos});
  }
  CheckQposQuaternions(session.engine().model(), out.qpos, what);
  return out;
}

}  // namespace

std::uint64_t Reset(world::Session& session, const ResetRequest& request) {
  // Everything is checked before anything is submitted: a bad request resets nothing.
  const int key = request.keyframe.empty() ? -1 : FindKeyframe(session, request.keyframe);
  physics::cmd::SetState after = JointWrites(session, request.joints, "per_articulation_qpos");
  physics::PhysicsEngine& engine = session.engine();
  std::uint64_t seq = request.randomize ? request.randomize() : 0;
  if (key >= 0) {
    seq = engine.ResetToKeyframe(key);
  } else if (!request.randomize) {
    seq = session.ResetToInitialState();
    if (seq == 0) seq = engine.Reset();
  }
  if (!after.qpos.empty()) seq = engine.Submit(std::move(after));
  return seq;
}

std::uint64_t ResetArticulation(world::Session& session, std::string_view articulation,
                                std::string_view keyframe) {
  const world::Articulation& a = RequireArticulation(session, articulation);
  try {
    return session.ResetArticulation(a.name(), keyframe);
  } catch (const OpError&) {
    throw;
  } catch (const Error& e) {
    Fail("unknown_keyframe", e.what());
  }
}

std::uint64_t SetPaused(world::Session& session, bool paused, When when) {
  if (when == When::kNow) {
    session.SetPaused(paused);
    return 0;
  }
  return session.engine().Submit(physics::cmd::SetPaused{paused});
}

int SetSpeed(world::Session& session, double percent) {
  if (!std::isfinite(percent)) Fail("bad_value", "'percent' must be finite");
  session.engine().SetSpeedPercent(static_cast<int>(std::lround(std::clamp(percent, 5.0, 100.0))));
  return session.engine().speed_percent();
}

std::uint64_t Forward(world::Session& session) {
  return session.engine().Submit(physics::cmd::Forward{});
}

std::uint64_t Step(world::Session& session, int steps) {
  CheckRange(steps, "n_steps");
  return session.engine().Submit(physics::cmd::Step{steps});
}

}  // namespace urlab::ops
