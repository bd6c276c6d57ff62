#include "urlab/physics/free_base.h"

#include <map>
#include <set>

namespace urlab::physics {
namespace {

bool Owned(const mjModel* m, mjtObj type, int id, std::string_view prefix) {
  const char* name = mj_id2name(m, type, id);
  return name && std::string_view(name).starts_with(prefix);
}

}  // namespace

int FreeBaseJoint(const mjModel* m, std::string_view prefix) {
  // The articulation's bodies: its named bodies and the bodies its joints move.
  std::set<int> bodies;
  for (int b = 1; b < m->nbody; ++b) {
    if (Owned(m, mjOBJ_BODY, b, prefix)) bodies.insert(b);
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (Owned(m, mjOBJ_JOINT, j, prefix)) bodies.insert(m->jnt_bodyid[j]);
  }
  std::map<int, int> bodies_under;  // top-level body -> how many of the articulation's bodies
  for (int b : bodies) {
    if (b > 0) ++bodies_under[m->body_rootid[b]];
  }
  int base = -1;
  int most = 0;
  for (const auto& [root, n] : bodies_under) {  // ordered by id: the first wins a tie
    if (n > most) {
      base = root;
      most = n;
    }
  }
  if (base < 0) return -1;
  for (int j = m->body_jntadr[base]; j >= 0 && j < m->body_jntadr[base] + m->body_jntnum[base];
       ++j) {
    if (m->jnt_type[j] == mjJNT_FREE && Owned(m, mjOBJ_JOINT, j, prefix)) return j;
  }
  return -1;
}

int FreeBaseIndex(const ArticulationBindings& bindings) {
  const int joint = FreeBaseJoint(bindings.model(), bindings.prefix());
  if (joint < 0) return -1;
  const auto& joints = bindings.joints().all();
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].id == joint) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace urlab::physics
