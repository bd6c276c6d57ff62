// State edits (urlab/ops/state.h).
#include "urlab/ops/state.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>

#include "ops/value_ranges.h"
#include "urlab/ops/error.h"
#include "urlab/ops/simulation.h"
#include "urlab/physics/free_base.h"

namespace urlab::ops {

std::uint64_t SetQpos(world::Session& session, std::string_view articulation,
                      const std::vector<double>& qpos) {
  const world::Articulation& a = RequireArticulation(session, articulation);
  CheckRanges(qpos, "qpos");
  // The articulation's qpos addresses in joint order, and its free base's.
  std::vector<int> adrs;
  for (const physics::JointView& j : a.bindings->joints().all()) {
    for (int k = 0; k < j.qpos_size; ++k) adrs.push_back(j.qpos_adr + k);
  }
  const int base = physics::FreeBaseIndex(*a.bindings);
  const int free_adr =
      base < 0 ? -1 : a.bindings->joints().all()[static_cast<std::size_t>(base)].qpos_adr;
  if (adrs.empty()) Fail("no_joints", a.name() + " has no joints");
  physics::cmd::SetState state;
  if (free_adr >= 0 && qpos.size() == 7 && adrs.size() != 7) {
    state.qpos.push_back({free_adr, qpos});
  } else if (qpos.size() == adrs.size()) {
    // One command, whatever the addresses' layout: runs of consecutive addresses.
    for (std::size_t i = 0; i < adrs.size(); ++i) {
      auto& runs = state.qpos;
      if (runs.empty() ||
          adrs[i] != runs.back().adr + static_cast<int>(runs.back().values.size())) {
        runs.push_back({adrs[i], {}});
      }
      runs.back().values.push_back(qpos[i]);
    }
  } else {
    Fail("dim_mismatch", a.name() + ": qpos needs " + std::to_string(adrs.size()) + " values" +
                             (free_adr >= 0 ? " (or 7 for the free base)" : "") + ", got " +
                             std::to_string(qpos.size()));
  }
  CheckQposQuaternions(session.engine().model(), state.qpos, "set_qpos");
  return session.engine().Submit(std::move(state));
}

int MocapIndex(const world::Session& session, std::string_view body) {
  const mjModel* m = session.engine().model();
  const std::string name(body);
  const int id = mj_name2id(m, mjOBJ_BODY, name.c_str());
  if (id < 0) Fail("unknown_body", "no body '" + name + "' (full name, with its prefix)");
  if (m->body_mocapid[id] < 0) Fail("not_mocap_body", "body '" + name + "' is not a mocap body");
  return m->body_mocapid[id];
}

std::uint64_t SetMocapPose(world::Session& session, std::string_view body,
                           const std::array<double, 3>& pos, const std::array<double, 4>& quat) {
  physics::cmd::SetMocap c;
  c.mocap_id = MocapIndex(session, body);
  CheckRanges({pos.begin(), pos.end()}, "pos");
  CheckRange(
      std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]),
      "quaternion norm", "the norm of quat");
  c.pos = pos;
  c.quat = quat;
  return session.engine().Submit(c);
}

const std::vector<const char*>& IntegratorNames() {
  static const std::vector<const char*> names = {"Euler", "RK4", "implicit"};
  return names;
}
const std::vector<const char*>& ConeNames() {
  static const std::vector<const char*> names = {"pyramidal", "elliptic"};
  return names;
}
const std::vector<const char*>& SolverNames() {
  static const std::vector<const char*> names = {"PGS", "CG", "Newton"};
  return names;
}

void ApplyOptions(const OptionsChange& ch, mjOption& o) {
  if (ch.timestep) o.timestep = *ch.timestep;
  if (ch.impratio) o.impratio = *ch.impratio;
  if (ch.tolerance) o.tolerance = *ch.tolerance;
  if (ch.density) o.density = *ch.density;
  if (ch.viscosity) o.viscosity = *ch.viscosity;
  if (ch.gravity) std::copy_n(ch.gravity->begin(), 3, o.gravity);
  if (ch.wind) std::copy_n(ch.wind->begin(), 3, o.wind);
  if (ch.magnetic) std::copy_n(ch.magnetic->begin(), 3, o.magnetic);
  if (ch.iterations) o.iterations = *ch.iterations;
  if (ch.integrator) o.integrator = *ch.integrator;
  if (ch.cone) o.cone = *ch.cone;
  if (ch.solver) o.solver = *ch.solver;
}

OptionsSet SetOptions(world::Session& session, const OptionsChange& ch) {
  // Validated on the caller's thread; the physics thread only copies values in.
  const auto number = [](const std::optional<double>& v, const char* field) {
    if (v) CheckRange(*v, field);
  };
  number(ch.timestep, "timestep");
  number(ch.impratio, "impratio");
  number(ch.tolerance, "tolerance");
  number(ch.density, "density");
  number(ch.viscosity, "viscosity");
  for (const auto& [v, field] : {std::pair{&ch.gravity, "gravity"}, std::pair{&ch.wind, "wind"},
                                 std::pair{&ch.magnetic, "magnetic"}}) {
    if (*v) CheckRanges({(*v)->begin(), (*v)->end()}, field);
  }
  if (ch.iterations) CheckRange(*ch.iterations, "iterations");
  const auto keyword = [](const std::optional<int>& v, const char* field,
                          const std::vector<const char*>& names) {
    if (v && (*v < 0 || *v >= static_cast<int>(names.size()))) {
      Fail("bad_value", std::string(field) + ": unknown value " + std::to_string(*v));
    }
  };
  keyword(ch.integrator, "integrator", IntegratorNames());
  keyword(ch.cone, "cone", ConeNames());
  keyword(ch.solver, "solver", SolverNames());
  OptionsSet out;
  out.options = std::make_shared<mjOption>();
  out.seq = session.engine().Submit(
      physics::cmd::SetOptions{[ch, result = out.options](mjOption& o) {
                                 ApplyOptions(ch, o);
                                 *result = o;  // read by the caller once the command is finished
                               },
                               "set_sim_options"});
  return out;
}

}  // namespace urlab::ops
