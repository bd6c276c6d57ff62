#pragma once
// get_contacts: the active contacts of the current state, with names, position, frame (the
// normal is its first row), penetration distance and the 6-vector force in the contact frame
// (mj_contactForce), optionally only those touching given bodies or geoms, at most a chosen
// number (the rest counted and flagged `truncated`).
//
// Threading: CollectContacts runs on the physics thread (an Inspect command: it reads mjData);
// the filter is built and the list is turned into a reply on the network I/O thread.
#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <vector>

#include "net/msgpack_codec.h"

namespace urlab::net {

// Object ids to match, -1 for any. A contact matches when its two sides match {body1, body2}
// (or {geom1, geom2}) in either order.
struct ContactFilter {
  int body1 = -1, body2 = -1, geom1 = -1, geom2 = -1;
};

struct ContactRecord {
  int geom1 = -1, geom2 = -1;
  std::array<double, 3> pos{};
  std::array<double, 9> frame{};
  double dist = 0;
  std::array<double, 6> force{};
};

struct ContactList {
  std::vector<ContactRecord> contacts;
  int matched = 0;  // contacts that passed the filter (more than contacts.size() when truncated)
  double time = 0;
};

// Physics thread: fills *out from d's contacts.
void CollectContacts(const mjModel* m, const mjData* d, const ContactFilter& filter,
                     int max_contacts, ContactList* out);

// The reply fields: contacts [{geom1, geom2, body1, body2 (names), pos, frame, normal, dist,
// force}], count, matched, truncated, time. Names come from `m` (immutable while running).
Json ContactsReply(const mjModel* m, const ContactList& list);

}  // namespace urlab::net
