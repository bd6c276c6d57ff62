#include "net/free_bodies.h"

#include <algorithm>
#include <set>
#include <string>

namespace urlab::net {

std::vector<FreeBodyEntry> FindFreeBodies(const world::Session& session,
                                          const std::vector<ArticulationTopics>& tables) {
  const mjModel* m = session.engine().model();
  std::set<int> owned;
  for (const ArticulationTopics& t : tables) owned.insert(t.body_ids.begin(), t.body_ids.end());
  std::vector<FreeBodyEntry> out;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_FREE) continue;
    const int body = m->jnt_bodyid[j];
    if (owned.count(body)) continue;
    FreeBodyEntry e;
    e.body = body;
    e.joint = j;
    e.qpos_adr = m->jnt_qposadr[j];
    e.dof_adr = m->jnt_dofadr[j];
    const char* body_name = mj_id2name(m, mjOBJ_BODY, body);
    const char* joint_name = mj_id2name(m, mjOBJ_JOINT, j);
    e.body_name = body_name ? body_name : "";
    e.joint_name = joint_name ? joint_name : "";
    e.name = body_name ? e.body_name : "body" + std::to_string(body);
    e.kind = "body";
    for (const world::PropLayout& p : session.props()) {
      if (p.body != body) continue;
      e.kind = "prop";
      e.name = p.name;
    }
    for (const world::LauncherLayout& l : session.launchers()) {
      if (std::find(l.bodies.begin(), l.bodies.end(), body) != l.bodies.end()) {
        e.kind = "projectile";
      }
    }
    out.push_back(std::move(e));
  }
  std::sort(out.begin(), out.end(),
            [](const FreeBodyEntry& a, const FreeBodyEntry& b) { return a.body < b.body; });
  return out;
}

Json FreeBodiesHello(const std::vector<FreeBodyEntry>& free_bodies) {
  Json map = Json::object();
  for (const FreeBodyEntry& b : free_bodies) {
    map[b.name] = Json{{"kind", b.kind},         {"body", b.body_name},
                       {"id", b.body},           {"free_joint", b.joint_name},
                       {"qpos_adr", b.qpos_adr}, {"qvel_adr", b.dof_adr}};
  }
  return map;
}

}  // namespace urlab::net
