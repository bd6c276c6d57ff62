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

// configure_controller's schema as the 2026 client reads it: {param: {type, min?, max?}}, a map
// per entry (the client calls .get on each and checks every value against min and max before
// sending). kp, kv and torque_limit are maps by actuator (or joint) name, the defaults one number;
// every gain is a finite number >= 0 (ops::SetGains) with no upper bound.
Json GainSchema() {
  const Json per_joint{{"type", "per_joint"}, {"min", 0.0}};
  const Json scalar{{"type", "scalar"}, {"min", 0.0}};
  return Json{{"kp", per_joint},      {"kv", per_joint},      {"torque_limit", per_joint},
              {"default_kp", scalar}, {"default_kv", scalar}, {"default_torque_limit", scalar}};
}

// One row of raw_joints: joint `id` under `name`, with its place in the entity's own vectors
// when it has one (qpos_index / qvel_index into arts[prefix].qpos / .qvel).
Json JointRow(const mjModel* m, int id, const std::string& name, Json qpos_index = Json(),
              Json qvel_index = Json()) {
  Json row{{"name", name},
           {"id", id},
           {"type", m->jnt_type[id]},
           {"qpos_adr", m->jnt_qposadr[id]},
           {"qvel_adr", m->jnt_dofadr[id]},
           {"range", {m->jnt_range[2 * id], m->jnt_range[2 * id + 1]}},
           {"body_id", m->jnt_bodyid[id]}};
  if (!qpos_index.is_null()) row["qpos_index"] = std::move(qpos_index);
  if (!qvel_index.is_null()) row["qvel_index"] = std::move(qvel_index);
  return row;
}

// The joint actuator `id` drives, -1 without one.
int ActuatorJoint(const mjModel* m, int id) {
  const int target = m->actuator_trnid[2 * id];
  const bool joint =
      m->actuator_trntype[id] == mjTRN_JOINT || m->actuator_trntype[id] == mjTRN_JOINTINPARENT;
  return joint && target >= 0 ? target : -1;
}

// One row of raw_actuators: actuator `id` under `name`, driving the joint named `joint` (null
// without one).
Json ActuatorRow(const mjModel* m, int id, const std::string& name, Json joint) {
  Json gear = Json::array();
  for (int k = 0; k < 6; ++k) gear.push_back(m->actuator_gear[6 * id + k]);
  return Json{{"name", name},
              {"id", id},
              {"ctrlrange", {m->actuator_ctrlrange[2 * id], m->actuator_ctrlrange[2 * id + 1]}},
              {"gear", std::move(gear)},
              {"joint", std::move(joint)}};
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
    Json types = Json::object();
    for (std::size_t a = 0; a < t.actuator_ids.size(); ++a) {
      types[t.actuator_names[a]] = ActuatorKind(m, t.actuator_ids[a]);
    }
    // By category, each element's name in the compiled model (live) -> its name as written in
    // the MJCF (original); unnamed elements have no row.
    const auto originals = [&](mjtObj type, const std::vector<int>& ids) {
      Json map = Json::object();
      for (int id : ids) {
        const char* full = mj_id2name(m, type, id);
        if (full) map[full] = world::ShortNameOf(m, type, id, t.name + "_");
      }
      return map;
    };
    std::vector<int> joint_ids, sensor_ids;
    for (const JointTopicEntry& j : t.joints) joint_ids.push_back(j.id);
    for (const SensorTopicEntry& s : t.sensors) sensor_ids.push_back(s.id);
    e["actuator_types"] = std::move(types);
    e["original_names"] = Json{{"actuators", originals(mjOBJ_ACTUATOR, t.actuator_ids)},
                               {"joints", originals(mjOBJ_JOINT, joint_ids)},
                               {"sensors", originals(mjOBJ_SENSOR, sensor_ids)},
                               {"bodies", originals(mjOBJ_BODY, t.body_ids)}};
    // The raw tables the client builds its name maps from when it has no local model.
    RawTables raw = EntityRawTables(m, t);
    e["raw_model"] = true;
    e["raw_joints"] = std::move(raw.joints);
    e["raw_actuators"] = std::move(raw.actuators);
    e["raw_sensors"] = std::move(raw.sensors);
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
    // Its body and joint: the name in the compiled model -> the name after "{name}_" (the
    // whole name without that prefix).
    const auto original = [&](const std::string& full) {
      Json map = Json::object();
      const std::string prefix = name + "_";
      if (!full.empty()) map[full] = full.starts_with(prefix) ? full.substr(prefix.size()) : full;
      return map;
    };
    // Its raw tables: the free joint alone (named as free_joint), no actuators or sensors.
    Json raw_joints = Json::array();
    if (b.joint >= 0) raw_joints.push_back(JointRow(m, b.joint, b.joint_name, Json(0), Json(0)));
    entities.push_back(Json{
        {"prefix", name},
        {"actor_name", name},
        {"actor_id", entities.size()},
        {"name", name},
        {"kind", b.kind},  // prop, projectile or body
        {"default_control_mode", "raw"},
        {"controller", {{"kind", "none"}, {"params", Json::object()}, {"schema", Json::object()}}},
        {"actuator_types", Json::object()},
        {"original_names",
         {{"actuators", Json::object()},
          {"joints", original(b.joint_name)},
          {"sensors", Json::object()},
          {"bodies", original(b.body_name)}}},
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
        {"sensors", Json::array()},
        {"raw_model", true},
        {"raw_joints", std::move(raw_joints)},
        {"raw_actuators", Json::array()},
        {"raw_sensors", Json::array()}});
  }
  return entities;
}

Json GlobalCameras(const mjModel* m, const world::CameraStreams* cameras) {
  return CameraMap(m, cameras, "");
}

Json RawJoints(const world::Session& session) {
  const mjModel* m = session.engine().model();
  Json joints = Json::array();
  for (int j = 0; j < m->njnt; ++j)
    joints.push_back(JointRow(m, j, ShortName(session, mjOBJ_JOINT, j)));
  return joints;
}

Json RawActuators(const world::Session& session) {
  const mjModel* m = session.engine().model();
  Json actuators = Json::array();
  for (int a = 0; a < m->nu; ++a) {
    const int joint = ActuatorJoint(m, a);
    actuators.push_back(
        ActuatorRow(m, a, ShortName(session, mjOBJ_ACTUATOR, a),
                    joint >= 0 ? Json(ShortName(session, mjOBJ_JOINT, joint)) : Json()));
  }
  return actuators;
}

RawTables EntityRawTables(const mjModel* m, const ArticulationTopics& t) {
  RawTables raw;
  // Where a run of addresses starts in the articulation's own vector (null when absent).
  const auto index = [](const std::vector<int>& adrs, int adr) {
    const auto it = std::find(adrs.begin(), adrs.end(), adr);
    return it == adrs.end() ? Json() : Json(it - adrs.begin());
  };
  for (std::size_t k = 0; k < t.joints.size(); ++k) {
    const JointTopicEntry& j = t.joints[k];
    raw.joints.push_back(JointRow(m, j.id, t.joint_names[k], index(t.qpos_adrs, j.qpos_adr),
                                  index(t.dof_adrs, j.dof_adr)));
  }
  for (std::size_t i = 0; i < t.actuator_ids.size(); ++i) {
    const int id = t.actuator_ids[i];
    const int joint = ActuatorJoint(m, id);
    Json row = ActuatorRow(
        m, id, t.actuator_names[i],
        joint >= 0 ? Json(world::ShortNameOf(m, mjOBJ_JOINT, joint, t.name + "_")) : Json());
    row["index"] = i;  // its place in arts[prefix].ctrl and in a step's ctrl vector
    raw.actuators.push_back(std::move(row));
  }
  for (std::size_t k = 0; k < t.sensors.size(); ++k) {
    const SensorTopicEntry& s = t.sensors[k];
    raw.sensors.push_back(Json{{"name", t.sensor_names[k]},
                               {"id", s.id},
                               {"type", m->sensor_type[s.id]},
                               {"adr", s.adr},
                               {"dim", s.dim}});
  }
  return raw;
}

}  // namespace urlab::net::dialect2026
