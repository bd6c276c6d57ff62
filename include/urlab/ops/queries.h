#pragma once
// Queries: the active contacts (the one contact extractor: the step server's get_contacts and the
// viewer's contact drawing both read CollectContacts) and the keyframes of the scene. One typed
// function per query with one validation (ops::OpError with the wire code).
//
// Threading: CollectContacts runs on the physics thread (an Inspect command, or a post-step
// callback: it reads mjData); QueryContacts and ListKeyframes on any thread.
#include <mujoco/mujoco.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "urlab/ops/error.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// One active contact.
struct Contact {
  int geom1 = -1, geom2 = -1;
  double pos[3] = {0, 0, 0};
  double frame[9] = {};  // rows: normal, tangent 1, tangent 2 (world)
  double dist = 0;       // penetration distance (negative: penetrating)
  double force[6] = {};  // in the contact frame (normal first), from mj_contactForce
};

// Object ids to match, -1 for any. A contact matches when its two sides match {body1, body2}
// (or {geom1, geom2}) in either order.
struct ContactFilter {
  int body1 = -1, body2 = -1, geom1 = -1, geom2 = -1;
};

struct ContactList {
  std::vector<Contact> contacts;
  int matched = 0;  // contacts that passed the filter (more than contacts.size() when truncated)
  double time = 0;
};

// Physics thread: fills *out from d's contacts (at most `max_contacts`; the rest are counted in
// `matched`). Reuses out's storage.
void CollectContacts(const mjModel* m, const mjData* d, const ContactFilter& filter,
                     int max_contacts, ContactList* out);

// get_contacts: names (full, with their prefix) to match, empty for any.
struct ContactsRequest {
  std::string body1, body2, geom1, geom2;
  int max_contacts = 64;  // in the range of max_contacts (bad_value)
};
struct ContactsQuery {
  std::uint64_t seq = 0;              // the inspection command; `list` is filled once it applied
  std::shared_ptr<ContactList> list;  // read it after WaitForCommand(seq)
};
// unknown_body for a body name, bad_value for a geom name or max_contacts out of range.
ContactsQuery QueryContacts(world::Session& session, const ContactsRequest& request);

// The scene's keyframes: each by short name beside its articulation (world/names.h), and its
// full name (what a reset always accepts).
struct KeyframeInfo {
  std::string name, articulation, full_name;  // articulation "" when none owns it
};
std::vector<KeyframeInfo> ListKeyframes(const world::Session& session);

}  // namespace urlab::ops
