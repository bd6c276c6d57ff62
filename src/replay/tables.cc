#include "urlab/replay/tables.h"

namespace urlab::replay {

namespace {

std::string NameOf(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? std::string(n) : std::string();
}

}  // namespace

int JointQposWidth(int type) { return type == mjJNT_FREE ? 7 : type == mjJNT_BALL ? 4 : 1; }

int JointDofWidth(int type) { return type == mjJNT_FREE ? 6 : type == mjJNT_BALL ? 3 : 1; }

const char* JointTypeName(int type) {
  switch (type) {
    case mjJNT_FREE:
      return "free";
    case mjJNT_BALL:
      return "ball";
    case mjJNT_SLIDE:
      return "slide";
    default:
      return "hinge";
  }
}

ModelTables ModelTables::Of(const mjModel* m, const std::vector<std::string>& articulations) {
  ModelTables t;
  t.nq = m->nq;
  t.nv = m->nv;
  t.na = m->na;
  t.nu = m->nu;
  t.nbody = m->nbody;
  t.nmocap = m->nmocap;
  t.nsensordata = m->nsensordata;
  t.timestep = m->opt.timestep;
  t.articulations = articulations;
  for (int j = 0; j < m->njnt; ++j) {
    JointEntry e;
    e.name = NameOf(m, mjOBJ_JOINT, j);
    e.type = m->jnt_type[j];
    e.qposadr = m->jnt_qposadr[j];
    e.dofadr = m->jnt_dofadr[j];
    e.nq = JointQposWidth(e.type);
    e.nv = JointDofWidth(e.type);
    std::size_t best = 0;
    for (const std::string& a : articulations) {
      const std::string prefix = a + "_";
      if (prefix.size() > best && e.name.size() > prefix.size() && e.name.starts_with(prefix)) {
        best = prefix.size();
        e.articulation = a;
      }
    }
    e.short_name = e.name.substr(best);
    t.joints.push_back(std::move(e));
  }
  for (int a = 0; a < m->nu; ++a) t.actuators.push_back({NameOf(m, mjOBJ_ACTUATOR, a), a, 1});
  for (int s = 0; s < m->nsensor; ++s) {
    t.sensors.push_back({NameOf(m, mjOBJ_SENSOR, s), m->sensor_adr[s], m->sensor_dim[s]});
  }
  for (int b = 0; b < m->nbody; ++b) {
    t.bodies.push_back(NameOf(m, mjOBJ_BODY, b));
    if (m->body_mocapid[b] >= 0) {
      t.mocap_bodies.push_back({t.bodies.back(), m->body_mocapid[b], 1});
    }
  }
  return t;
}

const JointEntry* ModelTables::FindJoint(std::string_view name) const {
  for (const JointEntry& j : joints) {
    if (j.name == name) return &j;
  }
  const JointEntry* found = nullptr;
  for (const JointEntry& j : joints) {
    if (j.short_name == name) {
      if (found) return nullptr;  // ambiguous
      found = &j;
    }
  }
  return found;
}

}  // namespace urlab::replay
