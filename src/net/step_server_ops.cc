// The step server's runtime operations: mocap poses, keyframes, physics options, contacts,
// counters, twist and controller configuration (docs/protocol.md, "Runtime operations"). Sessions,
// leases, stepping, resets and modes are in step_server.cc.
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
#include "urlab/world/names.h"

namespace urlab::net {

using namespace request;

namespace {
int MocapBody(const mjModel* m, const std::string& body) {
  const int id = mj_name2id(m, mjOBJ_BODY, body.c_str());
  if (id < 0) Fail("unknown_body", "no body '" + body + "' (full name, with its prefix)");
  if (m->body_mocapid[id] < 0) Fail("not_mocap_body", "body '" + body + "' is not a mocap body");
  return m->body_mocapid[id];
}
}  // namespace

StepServer::Outcome StepServer::SetMocapPose(Request& r) {
  const std::string body = String(r.body["body"], "body");
  const int mocap = MocapBody(session_.engine().model(), body);
  const physics::StateFrame* f = state_->Latest();
  physics::cmd::SetMocap c;
  c.mocap_id = mocap;
  std::copy_n(f->mocap_pos.begin() + 3 * mocap, 3, c.pos.begin());
  std::copy_n(f->mocap_quat.begin() + 4 * mocap, 4, c.quat.begin());
  if (const auto it = r.body.find("pos"); it != r.body.end()) {
    const std::vector<double> p = Numbers(*it, "pos");
    if (p.size() != 3) Fail("dim_mismatch", "pos needs 3 values");
    CheckRanges(p, "pos");
    std::copy(p.begin(), p.end(), c.pos.begin());
  }
  if (const auto it = r.body.find("quat"); it != r.body.end()) {
    const std::vector<double> q = Numbers(*it, "quat");
    if (q.size() != 4) Fail("dim_mismatch", "quat needs 4 values (w x y z)");
    CheckRange(std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]), "quaternion norm",
               "the norm of quat");
    std::copy(q.begin(), q.end(), c.quat.begin());
  }
  Outcome out;
  out.reply = Json{{"op", "set_mocap_pose_ok"}, {"body", body}};
  out.wait_for = session_.engine().Submit(c);
  out.on_applied = [this, mocap](Json& reply) {
    const physics::StateFrame* now = state_->Latest();
    reply["pos"] = Array(now->mocap_pos.data() + 3 * mocap, 3, false);
    reply["quat"] = Array(now->mocap_quat.data() + 4 * mocap, 4, false);
  };
  return out;
}

StepServer::Outcome StepServer::ReadMocapPose(Request& r) {
  const std::string body = String(r.body["body"], "body");
  const int mocap = MocapBody(session_.engine().model(), body);
  const physics::StateFrame* f = state_->Latest();
  return {Json{{"op", "read_mocap_pose_ok"},
               {"body", body},
               {"pos", Array(f->mocap_pos.data() + 3 * mocap, 3, false)},
               {"quat", Array(f->mocap_quat.data() + 4 * mocap, 4, false)}}};
}

StepServer::Outcome StepServer::ListKeyframes(Request&) {
  const mjModel* m = session_.engine().model();
  // Each keyframe by short name beside its articulation (world/names.h); the full name is what
  // `reset {keyframe_name}` always accepts.
  Json keys = Json::array();
  for (int k = 0; k < m->nkey; ++k) {
    const char* name = mj_id2name(m, mjOBJ_KEY, k);
    const world::Articulation* owner = name ? session_.OwnerOf(name) : nullptr;
    keys.push_back(Json{{"name", world::ShortNameOf(m, mjOBJ_KEY, k, owner ? owner->prefix : "")},
                        {"articulation", owner ? Json(owner->name()) : Json(nullptr)},
                        {"full_name", name ? name : ""}});
  }
  return {Json{{"op", "list_keyframes_ok"}, {"keyframes", keys}}};
}

StepServer::Outcome StepServer::SetSimOptions(Request& r) {
  const Json& options = r.body["options"];
  if (!options.is_object()) Fail("bad_value", "options must be a map");
  // Validate everything on this thread; the physics thread only copies values in.
  struct Change {
    std::optional<double> timestep, impratio, tolerance, density, viscosity;
    std::optional<std::array<double, 3>> gravity, wind, magnetic;
    std::optional<int> iterations, integrator, cone, solver;
  } ch;
  const auto vec3 = [](const Json& v, const char* f) {
    const std::vector<double> x = Numbers(v, f);
    if (x.size() != 3) Fail("dim_mismatch", std::string(f) + " needs 3 values");
    CheckRanges(x, f);
    return std::array<double, 3>{x[0], x[1], x[2]};
  };
  const auto keyword = [](const Json& v, const char* f, std::vector<const char*> names) {
    const std::string s = String(v, f);
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (s == names[i]) return static_cast<int>(i);
    }
    Fail("bad_value", std::string(f) + ": unknown value '" + s + "'");
  };
  for (const auto& [key, value] : options.items()) {
    // Each number within its range (value_range_table.cc); one bad field refuses them all.
    if (key == "timestep") {
      ch.timestep = RangedNumber(value, "timestep");
    } else if (key == "impratio") {
      ch.impratio = RangedNumber(value, "impratio");
    } else if (key == "tolerance") {
      ch.tolerance = RangedNumber(value, "tolerance");
    } else if (key == "density") {
      ch.density = RangedNumber(value, "density");
    } else if (key == "viscosity") {
      ch.viscosity = RangedNumber(value, "viscosity");
    } else if (key == "gravity") {
      ch.gravity = vec3(value, "gravity");
    } else if (key == "wind") {
      ch.wind = vec3(value, "wind");
    } else if (key == "magnetic") {
      ch.magnetic = vec3(value, "magnetic");
    } else if (key == "iterations") {
      ch.iterations = static_cast<int>(RangedNumber(value, "iterations"));
    } else if (key == "integrator") {
      ch.integrator = keyword(value, "integrator", {"Euler", "RK4", "implicit"});
    } else if (key == "cone") {
      ch.cone = keyword(value, "cone", {"pyramidal", "elliptic"});
    } else if (key == "solver") {
      ch.solver = keyword(value, "solver", {"PGS", "CG", "Newton"});
    } else {
      Fail("bad_value", "unknown option '" + key + "'");
    }
  }
  auto result = std::make_shared<mjOption>();
  Outcome out;
  out.reply = Json{{"op", "set_sim_options_ok"}};
  out.wait_for = session_.engine().Submit(physics::cmd::SetOptions{
      [ch, result](mjOption& o) {
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
        *result = o;  // read by the I/O thread once the command is finished
      },
      "set_sim_options"});
  out.on_applied = [result](Json& reply) {
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
  const mjModel* m = session_.engine().model();
  int max_contacts = 64;
  if (const auto it = r.body.find("max_contacts"); it != r.body.end()) {
    max_contacts = static_cast<int>(RangedNumber(*it, "max_contacts"));
  }
  ContactFilter filter;
  if (const auto it = r.body.find("filter"); it != r.body.end() && !it->is_null()) {
    if (!it->is_object()) Fail("bad_value", "filter must be a map (body1, body2, geom1, geom2)");
    for (const auto& [key, value] : it->items()) {
      const std::string name = String(value, "filter");
      if (key == "body1" || key == "body2") {
        const int id = mj_name2id(m, mjOBJ_BODY, name.c_str());
        if (id < 0) Fail("unknown_body", "no body '" + name + "' (full name, with its prefix)");
        (key == "body1" ? filter.body1 : filter.body2) = id;
      } else if (key == "geom1" || key == "geom2") {
        const int id = mj_name2id(m, mjOBJ_GEOM, name.c_str());
        if (id < 0) Fail("bad_value", "no geom '" + name + "' (full name, with its prefix)");
        (key == "geom1" ? filter.geom1 : filter.geom2) = id;
      } else {
        Fail("bad_value", "filter: unknown key '" + key + "' (body1, body2, geom1, geom2)");
      }
    }
  }
  auto list = std::make_shared<ContactList>();
  Outcome out;
  out.reply = Json{{"op", "get_contacts_ok"}};
  out.wait_for = session_.engine().Submit(
      physics::cmd::Inspect{[filter, max_contacts, list](const mjModel* model, const mjData* d) {
                              CollectContacts(model, d, filter, max_contacts, list.get());
                            },
                            "get_contacts"});
  out.on_applied = [m, list](Json& reply) {  // read once the command is finished
    Json fields = ContactsReply(m, *list);
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
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  if (!t.twist) Fail("no_twist_controller", t.name + " has no twist controller (no free base)");
  // linear [vx, vy, vz] in the base's heading frame, angular [wx, wy, yaw rate]: the planar parts
  // drive the twist controller (twist.h), which attaches; the rest must be given but is unused.
  const std::vector<double> linear = Numbers(Require(r.body, "linear"), "linear");
  const std::vector<double> angular = Numbers(Require(r.body, "angular"), "angular");
  if (linear.size() != 3) Fail("dim_mismatch", "linear needs 3 values");
  if (angular.size() != 3) Fail("dim_mismatch", "angular needs 3 values");
  t.twist->Attach(true);
  const control::Twist applied = t.twist->SetTwist({linear[0], linear[1], angular[2]});
  return {Json{{"op", "set_twist_ok"},
               {"articulation", t.name},
               {"linear", {applied.vx, applied.vy, 0.0}},
               {"angular", {0.0, 0.0, applied.yaw_rate}}}};
}

StepServer::Outcome StepServer::FireLauncher(Request& r) {
  const std::string name = String(r.body["launcher"], "launcher");
  if (!session_.FindLauncher(name)) {
    Fail("unknown_launcher", "no launcher '" + name + "' in the scene");
  }
  const world::Session::Launch launch = session_.FireLauncher(name);
  Outcome out;
  out.reply =
      Json{{"op", "fire_launcher_ok"}, {"launcher", name}, {"projectile", launch.projectile}};
  out.wait_for = launch.seq;  // answered once the projectile is on its way
  return out;
}

StepServer::Outcome StepServer::ConfigureController(Request& r) {
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  const Json& params = r.body["params"];
  if (!params.is_object()) Fail("controller_schema_violation", "params must be a map");
  auto* pd = dynamic_cast<control::PdController*>(t.control->controller());
  if (!pd) {
    Fail("no_controller", t.name + " has no configurable controller (PD gains only)");
  }
  // Schema: {"kp"|"kv"|"torque_limit": number (every actuator)} and/or
  // {"gains": {actuator or joint name: {"kp", "kv", "torque_limit"}}}. Validated whole first.
  const auto gain_value = [](const Json& v, const std::string& what) {
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0) {
      Fail("controller_schema_violation", what + " must be a finite number >= 0");
    }
    return v.get<double>();
  };
  const auto patch = [&](control::PdGains g, const Json& fields, const std::string& where) {
    for (const auto& [k, v] : fields.items()) {
      if (k == "kp") {
        g.kp = gain_value(v, where + "kp");
      } else if (k == "kv") {
        g.kv = gain_value(v, where + "kv");
      } else if (k == "torque_limit") {
        g.torque_limit = gain_value(v, where + "torque_limit");
      } else if (k != "gains" || !where.empty()) {
        Fail("controller_schema_violation", "unknown parameter '" + where + k + "'");
      }
    }
    return g;
  };
  const int n = static_cast<int>(t.actuator_ids.size());
  std::vector<control::PdGains> next(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) next[static_cast<std::size_t>(i)] = patch(pd->gains(i), params, "");
  if (const auto g = params.find("gains"); g != params.end()) {
    if (!g->is_object()) Fail("controller_schema_violation", "gains must be a map of name to map");
    for (const auto& [name, fields] : g->items()) {
      const auto it = t.gain_index.find(name);
      if (it == t.gain_index.end()) {
        Fail("controller_schema_violation", t.name + ": no actuator or joint '" + name + "'");
      }
      if (!fields.is_object()) Fail("controller_schema_violation", name + ": a map of gains");
      auto& slot = next[static_cast<std::size_t>(it->second)];
      slot = patch(slot, fields, name + ".");
    }
  }
  for (int i = 0; i < n; ++i) pd->SetGains(i, next[static_cast<std::size_t>(i)]);
  Json gains = Json::object();
  for (int i = 0; i < n; ++i) {
    const control::PdGains g = pd->gains(i);
    gains[t.actuator_names[static_cast<std::size_t>(i)]] =
        Json{{"kp", g.kp}, {"kv", g.kv}, {"torque_limit", g.torque_limit}};
  }
  return {Json{{"op", "configure_controller_ok"},
               {"articulation", t.name},
               {"kind", "pd"},
               {"params", Json{{"gains", std::move(gains)}}}}};
}

}  // namespace urlab::net
