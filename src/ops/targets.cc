// Targets (urlab/ops/targets.h).
#include "urlab/ops/targets.h"

#include <mujoco/mujoco.h>

#include <algorithm>

#include "ops/value_ranges.h"
#include "urlab/ops/controllers.h"

namespace urlab::ops {

namespace {

[[noreturn]] void Refuse(TargetsFault fault, std::string message) {
  static constexpr const char* kCodes[] = {"unknown_articulation", "dim_mismatch", "bad_value",
                                           "bad_value", "unknown_body"};
  throw TargetsError(fault, kCodes[static_cast<int>(fault)], std::move(message));
}

// The range check of the operations (bad_value), as a fault the topic can count.
void CheckValue(double x, std::string_view field, const std::string& what) {
  try {
    CheckRange(x, field, what);
  } catch (const OpError& e) {
    Refuse(TargetsFault::kOutOfRange, e.message);
  }
}

// The index of the body `name` (short or full) among the articulation's bodies, -1 when none.
int BodyIndex(const world::Articulation& a, std::string_view name) {
  const std::vector<std::string>& names = a.bindings->bodies().short_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name ||
        (name.size() == a.prefix.size() + names[i].size() && name.starts_with(a.prefix) &&
         name.substr(a.prefix.size()) == names[i])) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

void CheckOne(const world::Session& session, const ArticulationTargets& t, int force_steps,
              CheckedTargets::Patch* patch, std::vector<physics::cmd::ApplyForce>* forces) {
  const world::Articulation* a = session.FindArticulation(t.articulation);
  if (!a) {
    Refuse(TargetsFault::kUnknownArticulation,
           "no articulation '" + t.articulation + "' in the scene");
  }
  const std::string& name = t.articulation;
  const control::ArticulationControl& ctl = *a->control;
  const std::vector<int>& ids = ctl.actuator_ids();  // in id order
  patch->control = a->control;
  patch->values.clear();
  patch->raw = t.raw;
  if (t.ctrl) {
    for (const double v : *t.ctrl) CheckValue(v, "ctrl", name + ": ctrl");
    if (t.ctrl->size() != ids.size()) {
      Refuse(TargetsFault::kCount, name + ": ctrl has " + std::to_string(t.ctrl->size()) +
                                       " values, " + std::to_string(ids.size()) + " actuators");
    }
    for (std::size_t i = 0; i < ids.size(); ++i) {
      patch->values.emplace_back(static_cast<int>(i), (*t.ctrl)[i]);
    }
  }
  if (t.by_name.size() > ids.size() || t.by_id.size() > ids.size()) {
    Refuse(TargetsFault::kCount, name + ": " +
                                     std::to_string(std::max(t.by_name.size(), t.by_id.size())) +
                                     " targets for " + std::to_string(ids.size()) + " actuators");
  }
  if (!t.by_name.empty()) {
    const mjModel* m = session.engine().model();
    for (const auto& [actuator, value] : t.by_name) {
      const int i = ActuatorIndex(m, *a, actuator);
      if (i < 0) {
        Refuse(TargetsFault::kUnknownActuator, name + ": no actuator or joint '" + actuator + "'");
      }
      CheckValue(value, "ctrl_map", name + ": ctrl_map");
      patch->values.emplace_back(i, value);
    }
  }
  for (const auto& [id, value] : t.by_id) {
    const auto it = std::lower_bound(ids.begin(), ids.end(), id);
    if (it == ids.end() || *it != id) {
      Refuse(TargetsFault::kUnknownActuator,
             name + ": actuator " + std::to_string(id) + " is not one of this articulation");
    }
    CheckValue(value, "ctrl", name + ": ctrl");
    patch->values.emplace_back(static_cast<int>(it - ids.begin()), value);
  }
  for (const Wrench& w : t.wrenches) {
    const int i = BodyIndex(*a, w.body);
    if (i < 0) {
      Refuse(TargetsFault::kUnknownBody, name + ": no body '" + w.body + "' in this articulation");
    }
    for (const double v : w.values) CheckValue(v, "xfrc_applied", name + ": xfrc_applied");
    if (w.values.size() != 6) {
      Refuse(TargetsFault::kCount, name + ": xfrc_applied needs 6 values (force, torque)");
    }
    physics::cmd::ApplyForce f;
    f.body = a->bindings->bodies().all()[static_cast<std::size_t>(i)].id;
    std::copy_n(w.values.begin(), 3, f.force.begin());
    std::copy_n(w.values.begin() + 3, 3, f.torque.begin());
    f.steps = force_steps;  // for the whole window, cleared after it
    forces->push_back(f);
  }
}

}  // namespace

void CheckTargets(const world::Session& session, const TargetsRequest& request,
                  CheckedTargets* out) {
  CheckValue(request.force_steps, "n_steps", "the steps a force acts");
  out->source = request.source;
  out->forces.clear();
  // Kept, not cleared: each patch's storage is reused by the next request.
  if (out->patches.size() < request.articulations.size()) {
    out->patches.resize(request.articulations.size());
  }
  for (std::size_t i = 0; i < request.articulations.size(); ++i) {
    CheckOne(session, request.articulations[i], request.force_steps, &out->patches[i],
             &out->forces);
  }
  for (std::size_t i = request.articulations.size(); i < out->patches.size(); ++i) {
    out->patches[i].control = nullptr;
    out->patches[i].values.clear();
    out->patches[i].raw.reset();
  }
}

CheckedTargets CheckTargets(const world::Session& session, const TargetsRequest& request) {
  CheckedTargets out;
  CheckTargets(session, request, &out);
  return out;
}

void ApplyTargets(world::Session& session, const CheckedTargets& checked) {
  for (const CheckedTargets::Patch& p : checked.patches) {
    if (p.control && (!p.values.empty() || p.raw)) {
      p.control->channel(checked.source).Patch(p.values, p.raw);
    }
  }
  for (const physics::cmd::ApplyForce& f : checked.forces) session.engine().Submit(f);
}

void SetTargets(world::Session& session, const TargetsRequest& request) {
  ApplyTargets(session, CheckTargets(session, request));
}

}  // namespace urlab::ops
