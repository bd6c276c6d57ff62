// Controllers (urlab/ops/controllers.h).
#include "urlab/ops/controllers.h"

#include <mujoco/mujoco.h>

#include <cmath>
#include <limits>

#include "urlab/control/controllers.h"
#include "urlab/ops/error.h"
#include "urlab/ops/simulation.h"
#include "urlab/world/names.h"

namespace urlab::ops {

namespace {

constexpr double kKeep = std::numeric_limits<double>::quiet_NaN();

control::PdController& RequirePd(const world::Articulation& a) {
  auto* pd = dynamic_cast<control::PdController*>(a.control->controller());
  if (!pd) Fail("no_controller", a.name() + " has no configurable controller (PD gains only)");
  return *pd;
}

double GainValue(const std::optional<double>& v, const std::string& what) {
  if (v && (!std::isfinite(*v) || *v < 0)) {
    Fail("controller_schema_violation", what + " must be a finite number >= 0");
  }
  return v ? *v : kKeep;
}

std::vector<ActuatorGains> InEffect(const mjModel* m, const world::Articulation& a,
                                    const control::PdController& pd) {
  std::vector<ActuatorGains> out;
  for (int i = 0; i < a.control->num_actuators(); ++i) {
    const control::PdGains g = pd.gains(i);
    out.push_back(
        {world::ShortNameOf(m, mjOBJ_ACTUATOR,
                            a.control->actuator_ids()[static_cast<std::size_t>(i)], a.prefix),
         g.kp, g.kv, g.torque_limit});
  }
  return out;
}

}  // namespace

int ActuatorIndex(const mjModel* m, const world::Articulation& a, std::string_view name) {
  const std::vector<int>& ids = a.control->actuator_ids();
  // `full` names the element, or is its short name below the articulation's prefix.
  const auto names = [&](const char* full) {
    if (!full) return false;
    const std::string_view f(full);
    return f == name || (f.starts_with(a.prefix) && f.substr(a.prefix.size()) == name);
  };
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (names(mj_id2name(m, mjOBJ_ACTUATOR, ids[i]))) return static_cast<int>(i);
  }
  // A joint name reaches the actuator that drives it (clients key gains and targets by joint).
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const int id = ids[i];
    if (m->actuator_trntype[id] == mjTRN_JOINT &&
        names(mj_id2name(m, mjOBJ_JOINT, m->actuator_trnid[2 * id]))) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

std::vector<ActuatorGains> SetGains(world::Session& session, std::string_view articulation,
                                    const GainsRequest& request) {
  const world::Articulation& a = RequireArticulation(session, articulation);
  control::PdController& pd = RequirePd(a);
  const mjModel* m = session.engine().model();
  // Checked whole first: a bad name or value anywhere changes nothing.
  const auto n = static_cast<std::size_t>(a.control->num_actuators());
  std::vector<double> kp(n, kKeep), kv(n, kKeep), limit(n, kKeep);
  const auto apply = [&](std::size_t i, const GainChange& c, const std::string& where) {
    if (const double v = GainValue(c.kp, where + "kp"); !std::isnan(v)) kp[i] = v;
    if (const double v = GainValue(c.kv, where + "kv"); !std::isnan(v)) kv[i] = v;
    if (const double v = GainValue(c.torque_limit, where + "torque_limit"); !std::isnan(v)) {
      limit[i] = v;
    }
  };
  for (std::size_t i = 0; i < n; ++i) apply(i, request.all, "");
  if (!request.named.empty()) {
    for (const auto& [name, change] : request.named) {
      const int i = ActuatorIndex(m, a, name);
      if (i < 0) {
        Fail("controller_schema_violation", a.name() + ": no actuator or joint '" + name + "'");
      }
      apply(static_cast<std::size_t>(i), change, name + ".");
    }
  }
  // The controller's own gains (what a frame without overrides leaves in effect), then the
  // frames: the physics thread applies, and the recorder records, the frame's kp and kv.
  for (std::size_t i = 0; i < n; ++i) {
    control::PdGains g = pd.gains(static_cast<int>(i));
    if (!std::isnan(kp[i])) g.kp = kp[i];
    if (!std::isnan(kv[i])) g.kv = kv[i];
    if (!std::isnan(limit[i])) g.torque_limit = limit[i];
    pd.SetGains(static_cast<int>(i), g);
  }
  for (int s = 0; s < control::kNumControlSources; ++s) {
    a.control->channel(static_cast<control::ControlSource>(s)).PatchGains(kp, kv);
  }
  return InEffect(m, a, pd);
}

std::vector<ActuatorGains> Gains(world::Session& session, std::string_view articulation) {
  const world::Articulation& a = RequireArticulation(session, articulation);
  return InEffect(session.engine().model(), a, RequirePd(a));
}

void SetControlSource(world::Session& session, std::string_view source,
                      std::string_view articulation) {
  const auto parsed = control::ParseControlSource(source);
  if (!parsed) Fail("bad_value", "source must be network, ui, input, hold or replay");
  if (articulation.empty()) {
    session.controls().SetGlobalSource(*parsed);
  } else {
    RequireArticulation(session, articulation).control->SetSourceOverride(*parsed);
  }
}

control::TwistController& RequireTwist(world::Session& session, std::string_view articulation) {
  const world::Articulation& a = RequireArticulation(session, articulation);
  control::TwistController* t = a.control->twist();
  if (!t) Fail("no_twist_controller", a.name() + " has no twist controller (no free base)");
  return *t;
}

control::Twist SetTwist(world::Session& session, std::string_view articulation,
                        const control::Twist& twist) {
  control::TwistController& t = RequireTwist(session, articulation);
  if (!std::isfinite(twist.vx) || !std::isfinite(twist.vy) || !std::isfinite(twist.yaw_rate)) {
    Fail("bad_value", "the twist must be finite");
  }
  t.Attach(true);
  return t.SetTwist(twist);
}

world::Session::Launch FireLauncher(world::Session& session, std::string_view name) {
  if (!session.FindLauncher(name)) {
    Fail("unknown_launcher", "no launcher '" + std::string(name) + "' in the scene");
  }
  return session.FireLauncher(name);
}

}  // namespace urlab::ops
