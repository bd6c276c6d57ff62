#include "net/dialect_2026_hello.h"

#include <algorithm>
#include <string>

#include "urlab/ops/controllers.h"
#include "urlab/world/names.h"

namespace urlab::net::dialect2026 {

namespace {

// The name of element `id` as written in its articulation's MJCF (composition prefixes it).
std::string ShortName(const world::Session& session, mjtObj type, int id) {
  const mjModel* m = session.engine().model();
  const char* full = mj_id2name(m, type, id);
  if (!full) return "";
  const std::string_view name = full;
  for (const world::Articulation& a : session.articulations()) {
    if (name.starts_with(a.prefix)) return std::string(name.substr(a.prefix.size()));
  }
  return std::string(name);
}

// A camera stream as the 2026 client reads it: {mode, resolution, fovy, zmq_endpoint,
// zmq_topic}.
Json CameraEntry(const mjModel* m, const world::CameraStreamInfo& s) {
  int id = mj_name2id(m, mjOBJ_CAMERA, (s.articulation + "_" + s.camera).c_str());
  if (id < 0) id = mj_name2id(m, mjOBJ_CAMERA, s.camera.c_str());
  return Json{{"mode", s.mode},
              {"resolution", {s.width, s.height}},
              {"fovy", id >= 0 ? Json(m->cam_fovy[id]) : Json(nullptr)},
              {"zmq_endpoint", s.endpoint},
              {"zmq_topic", s.header_topic},  // frames behind the UCM1 header
              {"bare_topic", s.topic},
              {"meta_topic", s.meta_topic},
              {"camera", s.camera},
              {"rate", s.rate}};
}

Json CameraMap(const mjModel* m, const world::CameraStreams* cameras,
               const std::string& articulation) {
  Json map = Json::object();
  if (!cameras) return map;
  for (const world::CameraStreamInfo& s : cameras->Streams()) {
    if (s.articulation == articulation) map[s.stream] = CameraEntry(m, s);
  }
  return map;
}

// configure_controller's schema: the keys it takes and their types.
Json GainSchema() {
  return Json{
      {"kp", "map<name,float>"}, {"kv", "map<name,float>"}, {"torque_limit", "map<name,float>"},
      {"default_kp", "float"},   {"default_kv", "float"},   {"default_torque_limit", "float"}};
}

}  // namespace

const char* ActuatorKind(const mjModel* m, int id) {
  const mjtNum* bias = m->actuator_biasprm + id * mjNBIAS;
  if (m->actuator_biastype[id] == mjBIAS_AFFINE) {
    if (bias[1] != 0) return "position";
    if (bias[2] != 0) return "velocity";
    return "general";
  }
  if (m->actuator_biastype[id] == mjBIAS_NONE && m->actuator_gaintype[id] == mjGAIN_FIXED &&
      m->actuator_dyntype[id] == mjDYN_NONE) {
    return "motor";
  }
  return "general";
}

Json Entities(world::Session& session, const std::vector<ArticulationTopics>& tables,
              const std::vector<FreeBodyEntry>& free_bodies, const world::CameraStreams* cameras,
              const Json& ours) {
  const mjModel* m = session.engine().model();
  Json entities = Json::array();
  for (std::size_t i = 0; i < tables.size(); ++i) {
    const ArticulationTopics& t = tables[i];
    const world::Articulation* wa = session.FindArticulation(t.name);
    const std::string kind = wa ? wa->config.controller.type : "none";
    const bool controlled = kind != "none" && kind != "passthrough";
    Json e;
    e["prefix"] = t.name;
    e["actor_name"] = t.name;
    e["actor_id"] = i;
    e["name"] = t.name;
    e["kind"] = "articulation";
    e["default_control_mode"] = controlled ? "ue_controller" : "raw";
    // The controller: its kind, its gains now (per-name maps, as configure_controller echoes
    // them) and what configure_controller takes (empty: it has no gains to set).
    Json params = Json::object(), schema = Json::object();
    try {
      Json kp = Json::object(), kv = Json::object(), limit = Json::object();
      for (const ops::ActuatorGains& g : ops::Gains(session, t.name)) {
        kp[g.actuator] = g.kp;
        kv[g.actuator] = g.kv;
        limit[g.actuator] = g.torque_limit;
      }
      params = Json{{"kp", std::move(kp)}, {"kv", std::move(kv)}, {"torque_limit", limit}};
      schema = GainSchema();
    } catch (const ops::OpError&) {  // no PD gains
    }
    e["controller"] = Json{{"kind", kind}, {"params", params}, {"schema", schema}};
    Json types = Json::object(), original = Json::object();
    for (std::size_t a = 0; a < t.actuator_ids.size(); ++a) {
      types[t.actuator_names[a]] = ActuatorKind(m, t.actuator_ids[a]);
    }
    // Each element's short name (as written in the MJCF) -> its name in the compiled model.
    const auto originals = [&](mjtObj type, const std::vector<int>& ids) {
      for (int id : ids) {
        const char* full = mj_id2name(m, type, id);
        if (full) original[world::ShortNameOf(m, type, id, t.name + "_")] = full;
      }
    };
    std::vector<int> joint_ids, sensor_ids;
    for (const JointTopicEntry& j : t.joints) joint_ids.push_back(j.id);
    for (const SensorTopicEntry& s : t.sensors) sensor_ids.push_back(s.id);
    originals(mjOBJ_JOINT, joint_ids);
    originals(mjOBJ_ACTUATOR, t.actuator_ids);
    originals(mjOBJ_SENSOR, sensor_ids);
    originals(mjOBJ_BODY, t.body_ids);
    e["actuator_types"] = std::move(types);
    e["original_names"] = std::move(original);
    e["camera_topics"] = CameraMap(m, cameras, t.name);
    // The free base: its root body's id, the free joint and where its state sits.
    const bool free = t.free_joint >= 0;
    const JointTopicEntry* fj = free ? &t.joints[static_cast<std::size_t>(t.free_joint)] : nullptr;
    e["id"] = fj ? m->jnt_bodyid[fj->id] : (t.body_ids.empty() ? -1 : t.body_ids.front());
    e["has_free_base"] = free;
    e["free_joint"] = fj ? Json(t.joint_names[static_cast<std::size_t>(t.free_joint)]) : Json();
    // Offsets into the articulation's own qpos / qvel (arts[prefix].qpos), where the root pose
    // (x y z, w x y z) and twist start.
    const auto offset = [](const std::vector<int>& adrs, int adr) {
      const auto it = std::find(adrs.begin(), adrs.end(), adr);
      return it == adrs.end() ? Json() : Json(it - adrs.begin());
    };
    e["qpos_offset"] = fj ? offset(t.qpos_adrs, fj->qpos_adr) : Json();
    e["qvel_offset"] = fj ? offset(t.dof_adrs, fj->dof_adr) : Json();
    if (i < ours.size()) {
      for (const char* field : {"joints", "actuators", "sensors"}) {
        if (ours[i].contains(field)) e[field] = ours[i][field];
      }
    }
    entities.push_back(std::move(e));
  }
  for (const FreeBodyEntry& b : free_bodies) {
    const std::string& name = b.name;
    // Its body and joint: the name after "{name}_" (the whole name without that prefix) ->
    // the name in the compiled model.
    Json original = Json::object();
    for (const std::string& full : {b.body_name, b.joint_name}) {
      if (full.empty()) continue;
      const std::string prefix = name + "_";
      original[full.starts_with(prefix) ? full.substr(prefix.size()) : full] = full;
    }
    entities.push_back(Json{
        {"prefix", name},
        {"actor_name", name},
        {"actor_id", entities.size()},
        {"name", name},
        {"kind", b.kind},  // prop, projectile or body
        {"default_control_mode", "raw"},
        {"controller", {{"kind", "none"}, {"params", Json::object()}, {"schema", Json::object()}}},
        {"actuator_types", Json::object()},
        {"original_names", std::move(original)},
        {"camera_topics", Json::object()},
        {"id", b.body},
        {"body", b.body_name},
        {"has_free_base", true},
        {"free_joint", b.joint_name.empty() ? Json() : Json(b.joint_name)},
        {"qpos_offset", 0},  // scene[name].qpos is the free joint's 7 values
        {"qvel_offset", 0},
        {"qpos_adr", b.qpos_adr},  // in the whole model (raw_joints)
        {"qvel_adr", b.dof_adr},
        {"joints", Json::array()},
        {"actuators", Json::array()},
        {"sensors", Json::array()}});
  }
  return entities;
}

Json GlobalCameras(const mjModel* m, const world::CameraStreams* cameras) {
  return CameraMap(m, cameras, "");
}

Json RawJoints(const world::Session& session) {
  const mjModel* m = session.engine().model();
  Json joints = Json::array();
  for (int j = 0; j < m->njnt; ++j) {
    joints.push_back(Json{{"name", ShortName(session, mjOBJ_JOINT, j)},
                          {"id", j},
                          {"type", m->jnt_type[j]},
                          {"qpos_adr", m->jnt_qposadr[j]},
                          {"qvel_adr", m->jnt_dofadr[j]},
                          {"range", {m->jnt_range[2 * j], m->jnt_range[2 * j + 1]}},
                          {"body_id", m->jnt_bodyid[j]}});
  }
  return joints;
}

Json RawActuators(const world::Session& session) {
  const mjModel* m = session.engine().model();
  Json actuators = Json::array();
  for (int a = 0; a < m->nu; ++a) {
    const int target = m->actuator_trnid[2 * a];
    const bool joint =
        (m->actuator_trntype[a] == mjTRN_JOINT || m->actuator_trntype[a] == mjTRN_JOINTINPARENT) &&
        target >= 0;
    Json gear = Json::array();
    for (int k = 0; k < 6; ++k) gear.push_back(m->actuator_gear[6 * a + k]);
    actuators.push_back(
        Json{{"name", ShortName(session, mjOBJ_ACTUATOR, a)},
             {"id", a},
             {"ctrlrange", {m->actuator_ctrlrange[2 * a], m->actuator_ctrlrange[2 * a + 1]}},
             {"gear", std::move(gear)},
             {"joint", joint ? Json(ShortName(session, mjOBJ_JOINT, target)) : Json()}});
  }
  return actuators;
}

}  // namespace urlab::net::dialect2026
