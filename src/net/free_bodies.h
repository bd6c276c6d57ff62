#pragma once
// Free bodies: the bodies with a free joint that belong to no articulation (a dynamic prop, a
// launcher's projectiles, a free body of no articulation's MJCF). The 2026 dialect lists them in
// hello's `entities` array and publishes their state under `scene` (ours: `entities`) in every
// observation (docs/protocol.md). Resolved once at BeginPlay from the compiled model, immutable
// afterwards.
// Thread: any (pure; the tables are read without locks once built).
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "net/msgpack_codec.h"
#include "net/topic_table.h"
#include "urlab/world/session.h"

namespace urlab::net {

struct FreeBodyEntry {
  // Its key (the 2026 entity's prefix and actor_name, the `scene` map's key): a prop's name for
  // a prop's body, else the body's name in the compiled model ("body{id}" when unnamed).
  std::string name;
  std::string kind;        // "prop", "projectile" (of a launcher) or "body"
  std::string body_name;   // in the compiled model ("" when unnamed)
  std::string joint_name;  // the free joint's, as raw_joints names it ("" when unnamed)
  int body = -1, joint = -1;
  int qpos_adr = 0, dof_adr = 0;  // the free joint's 7 qpos (x y z w x y z) and 6 dofs
};

// Every free body of `session`'s model whose body is none of `tables`' articulation bodies, in
// body id order.
std::vector<FreeBodyEntry> FindFreeBodies(const world::Session& session,
                                          const std::vector<ArticulationTopics>& tables);

// Our hello's `entities`: {name: {kind, body, id, free_joint, qpos_adr, qvel_adr}}.
Json FreeBodiesHello(const std::vector<FreeBodyEntry>& free_bodies);

}  // namespace urlab::net
