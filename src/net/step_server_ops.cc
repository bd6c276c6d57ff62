// The step server's runtime operations: mocap poses, keyframes, physics options, contacts,
// counters, twist and controller configuration (docs/protocol.md, "Runtime operations"). Each
// handler reads the wire's fields into an operation's typed request (urlab/ops/*.h), calls it and
// writes the reply. Sessions, leases, stepping, resets and modes are in step_server.cc.
#include <mujoco/mujoco.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>

#include "net/contacts.h"
#include "net/observation.h"
#include "net/request_fields.h"
#include "net/step_server.h"
#include "net/value_ranges.h"
#include "urlab/control/controllers.h"
#include "urlab/ops/controllers.h"
#include "urlab/ops/queries.h"
#include "urlab/ops/simulation.h"
#include "urlab/ops/state.h"
#include "urlab/world/names.h"

namespace urlab::net {

using namespace request;

StepServer::Outcome StepServer::SetMocapPose(Request& r) {
  const std::string body = String(r.body["body"], "body");
  const int mocap = ops::MocapIndex(session_, body);
  // Absent parts keep the pose the newest frame shows.
  const physics::StateFrame* f = state_->Latest();
  std::array<double, 3> pos;
  std::array<double, 4> quat;
  std::copy_n(f->mocap_pos.begin() + 3 * mocap, 3, pos.begin());
  std::copy_n(f->mocap_quat.begin() + 4 * mocap, 4, quat.begin());
  if (const auto it = r.body.find("pos"); it != r.body.end()) {
    const std::vector<double> p = Numbers(*it, "pos");
    if (p.size() != 3) Fail("dim_mismatch", "pos needs 3 values");
    std::copy(p.begin(), p.end(), pos.begin());
  }
  if (const auto it = r.body.find("quat"); it != r.body.end()) {
    const std::vector<double> q = Numbers(*it, "quat");
    if (q.size() != 4) Fail("dim_mismatch", "quat needs 4 values (w x y z)");
    std::copy(q.begin(), q.end(), quat.begin());
  }
  Outcome out;
  out.reply = Json{{"op", "set_mocap_pose_ok"}, {"body", body}};
  out.wait_for = ops::SetMocapPose(session_, body, pos, quat);
  out.on_applied = [this, mocap](Json& reply) {
    const physics::StateFrame* now = state_->Latest();
    reply["pos"] = Array(now->mocap_pos.data() + 3 * mocap, 3, false);
    reply["quat"] = Array(now->mocap_quat.data() + 4 * mocap, 4, false);
  };
  return out;
}

StepServer::Outcome StepServer::ReadMocapPose(Request& r) {
  const std::string body = String(r.body["body"], "body");
  const int mocap = ops::MocapIndex(session_, body);
  const physics::StateFrame* f = state_->Latest();
  return {Json{{"op", "read_mocap_pose_ok"},
               {"body", body},
               {"pos", Array(f->mocap_pos.data() + 3 * mocap, 3, false)},
               {"quat", Array(f->mocap_quat.data() + 4 * mocap, 4, false)}}};
}

StepServer::Outcome StepServer::ListKeyframes(Request&) {
  // Each keyframe's names and its record: time, qpos, qvel, ctrl and mocap poses (whole model).
  const mjModel* m = session_.engine().model();
  const auto row = [](const mjtNum* v, int key, int n) {
    return Array(v + static_cast<std::ptrdiff_t>(key) * n, static_cast<std::size_t>(n), false);
  };
  Json keys = Json::array();
  for (const ops::KeyframeInfo& k : ops::ListKeyframes(session_)) {
    Json record{{"name", k.name},
                {"articulation", k.articulation.empty() ? Json(nullptr) : Json(k.articulation)},
                {"full_name", k.full_name}};
    if (const int key = mj_name2id(m, mjOBJ_KEY, k.full_name.c_str()); key >= 0) {
      record["time"] = m->key_time[key];
      record["qpos"] = row(m->key_qpos, key, m->nq);
      record["qvel"] = row(m->key_qvel, key, m->nv);
      record["ctrl"] = row(m->key_ctrl, key, m->nu);
      record["mocap_pos"] = row(m->key_mpos, key, 3 * m->nmocap);
      record["mocap_quat"] = row(m->key_mquat, key, 4 * m->nmocap);
    }
    keys.push_back(std::move(record));
  }
  return {Json{{"op", "list_keyframes_ok"}, {"keyframes", keys}}};
}

StepServer::Outcome StepServer::SetSimOptions(Request& r) {
  const Json& options = r.body["options"];
  if (!options.is_object()) Fail("bad_value", "options must be a map");
  // The wire's names and types to the typed change; ops::SetOptions checks the ranges.
  ops::OptionsChange ch;
  const auto vec3 = [](const Json& v, const char* f) {
    const std::vector<double> x = Numbers(v, f);
    if (x.size() != 3) Fail("dim_mismatch", std::string(f) + " needs 3 values");
    return std::array<double, 3>{x[0], x[1], x[2]};
  };
  const auto keyword = [](const Json& v, const char* f, const std::vector<const char*>& names) {
    const std::string s = String(v, f);
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (s == names[i]) return static_cast<int>(i);
    }
    Fail("bad_value", std::string(f) + ": unknown value '" + s + "'");
  };
  for (const auto& [key, value] : options.items()) {
    if (key == "timestep") {
      ch.timestep = Number(value, "timestep");
    } else if (key == "impratio") {
      ch.impratio = Number(value, "impratio");
    } else if (key == "tolerance") {
      ch.tolerance = Number(value, "tolerance");
    } else if (key == "density") {
      ch.density = Number(value, "density");
    } else if (key == "viscosity") {
      ch.viscosity = Number(value, "viscosity");
    } else if (key == "gravity") {
      ch.gravity = vec3(value, "gravity");
    } else if (key == "wind") {
      ch.wind = vec3(value, "wind");
    } else if (key == "magnetic") {
      ch.magnetic = vec3(value, "magnetic");
    } else if (key == "iterations") {
      const double n = Number(value, "iterations");
      CheckRange(n, "iterations");  // a whole number before it becomes an int
      ch.iterations = static_cast<int>(n);
    } else if (key == "integrator") {
      ch.integrator = keyword(value, "integrator", ops::IntegratorNames());
    } else if (key == "cone") {
      ch.cone = keyword(value, "cone", ops::ConeNames());
    } else if (key == "solver") {
      ch.solver = keyword(value, "solver", ops::SolverNames());
    } else {
      Fail("bad_value", "unknown option '" + key + "'");
    }
  }
  const ops::OptionsSet set = ops::SetOptions(session_, ch);
  Outcome out;
  out.reply = Json{{"op", "set_sim_options_ok"}};
  out.wait_for = set.seq;
  out.on_applied = [result = set.options](Json& reply) {
    const mjOption& o = *result;
    reply["options"] = Json{{"timestep", o.timestep},
                            {"gravity", {o.gravity[0], o.gravity[1], o.gravity[2]}},
                            {"wind", {o.wind[0], o.wind[1], o.wind[2]}},
                            {"magnetic", {o.magnetic[0], o.magnetic[1], o.magnetic[2]}},
                            {"density", o.density},
                            {"viscosity", o.viscosity},
                            {"impratio", o.impratio},
                            {"tolerance", o.tolerance},
                            {"iterations", o.iterations},
                            {"integrator", o.integrator},
                            {"cone", o.cone},
                            {"solver", o.solver}};
  };
  return out;
}

StepServer::Outcome StepServer::GetContacts(Request& r) {
  ops::ContactsRequest request;
  if (const auto it = r.body.find("max_contacts"); it != r.body.end()) {
    request.max_contacts = static_cast<int>(RangedNumber(*it, "max_contacts"));
  }
  if (const auto it = r.body.find("filter"); it != r.body.end() && !it->is_null()) {
    if (!it->is_object()) Fail("bad_value", "filter must be a map (body1, body2, geom1, geom2)");
    for (const auto& [key, value] : it->items()) {
      std::string* slot = key == "body1"   ? &request.body1
                          : key == "body2" ? &request.body2
                          : key == "geom1" ? &request.geom1
                          : key == "geom2" ? &request.geom2
                                           : nullptr;
      if (!slot)
        Fail("bad_value", "filter: unknown key '" + key + "' (body1, body2, geom1, geom2)");
      *slot = String(value, "filter");
    }
  }
  const ops::ContactsQuery query = ops::QueryContacts(session_, request);
  Outcome out;
  out.reply = Json{{"op", "get_contacts_ok"}};
  out.wait_for = query.seq;
  out.on_applied = [m = session_.engine().model(), list = query.list](Json& reply) {
    Json fields = ContactsReply(m, *list);  // read once the command is finished
    for (auto& [k, v] : fields.items()) reply[k] = std::move(v);
  };
  return out;
}

StepServer::Outcome StepServer::GetCounters(Request&) {
  Json errors = Json::object();
  for (const auto& [code, n] : errors_) errors[code] = n;
  return {Json{{"op", "get_counters_ok"},
               {"errors", errors},
               {"clients", clients_.size()},
               {"driver", driver_.empty() ? Json() : Json(driver_)},
               {"mode", mode_}}};
}

StepServer::Outcome StepServer::SetTwist(Request& r) {
  const std::string name = String(r.body["articulation"], "articulation");
  if (r.v2026) {
    // The 2026 client sends a twist to every robot: one without a twist controller (a fixed
    // base) answers a silent success that applied nothing.
    ops::RequireArticulation(session_, name);
    try {
      ops::RequireTwist(session_, name);
    } catch (const ops::OpError& e) {
      if (e.code != "no_twist_controller") throw;
      return {Json{{"op", "set_twist_ok"},
                   {"articulation", name},
                   {"linear", {0.0, 0.0, 0.0}},
                   {"angular", {0.0, 0.0, 0.0}},
                   {"applied", false}}};
    }
  }
  ops::RequireTwist(session_, name);  // before the fields: a fixed base is the first thing wrong
  // linear [vx, vy, vz] in the base's heading frame, angular [wx, wy, yaw rate]: the planar parts
  // drive the twist controller (twist.h), which attaches; the rest must be given but is unused.
  const std::vector<double> linear = Numbers(Require(r.body, "linear"), "linear");
  const std::vector<double> angular = Numbers(Require(r.body, "angular"), "angular");
  if (linear.size() != 3) Fail("dim_mismatch", "linear needs 3 values");
  if (angular.size() != 3) Fail("dim_mismatch", "angular needs 3 values");
  const control::Twist applied = ops::SetTwist(session_, name, {linear[0], linear[1], angular[2]});
  return {Json{{"op", "set_twist_ok"},
               {"articulation", name},
               {"linear", {applied.vx, applied.vy, 0.0}},
               {"angular", {0.0, 0.0, applied.yaw_rate}}}};
}

StepServer::Outcome StepServer::FireLauncher(Request& r) {
  const std::string name = String(r.body["launcher"], "launcher");
  const world::Session::Launch launch = ops::FireLauncher(session_, name);
  Outcome out;
  out.reply =
      Json{{"op", "fire_launcher_ok"}, {"launcher", name}, {"projectile", launch.projectile}};
  out.wait_for = launch.seq;  // answered once the projectile is on its way
  return out;
}

StepServer::Outcome StepServer::ConfigureController(Request& r) {
  const std::string name = String(r.body["articulation"], "articulation");
  ops::RequireArticulation(session_, name);
  const Json& params = r.body["params"];
  if (!params.is_object()) Fail("controller_schema_violation", "params must be a map");
  // Schema: {"kp"|"kv"|"torque_limit": number (every actuator)} and/or
  // {"gains": {actuator or joint name: {"kp", "kv", "torque_limit"}}}; ops::SetGains checks the
  // names and values.
  const auto change = [](const Json& fields, const std::string& where) {
    ops::GainChange c;
    for (const auto& [k, v] : fields.items()) {
      std::optional<double>* slot = k == "kp"             ? &c.kp
                                    : k == "kv"           ? &c.kv
                                    : k == "torque_limit" ? &c.torque_limit
                                                          : nullptr;
      if (!slot) {
        if (k == "gains" && where.empty()) continue;
        Fail("controller_schema_violation", "unknown parameter '" + where + k + "'");
      }
      if (!v.is_number()) {
        Fail("controller_schema_violation", where + k + " must be a finite number >= 0");
      }
      *slot = v.get<double>();
    }
    return c;
  };
  ops::GainsRequest request;
  request.all = change(params, "");
  if (const auto g = params.find("gains"); g != params.end()) {
    if (!g->is_object()) Fail("controller_schema_violation", "gains must be a map of name to map");
    for (const auto& [actuator, fields] : g->items()) {
      if (!fields.is_object()) Fail("controller_schema_violation", actuator + ": a map of gains");
      request.named.emplace_back(actuator, change(fields, actuator + "."));
    }
  }
  Json gains = Json::object();
  for (const ops::ActuatorGains& g : ops::SetGains(session_, name, request)) {
    gains[g.actuator] = Json{{"kp", g.kp}, {"kv", g.kv}, {"torque_limit", g.torque_limit}};
  }
  return {Json{{"op", "configure_controller_ok"},
               {"articulation", name},
               {"kind", "pd"},
               {"params", Json{{"gains", std::move(gains)}}}}};
}

}  // namespace urlab::net
