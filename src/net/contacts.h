#pragma once
// get_contacts' reply: the wire encoding of the contacts ops::QueryContacts collected (the one
// contact extractor, urlab/ops/queries.h), with names, position, frame (the normal is its first
// row), penetration distance and the 6-vector force in the contact frame.
//
// Threading: the network I/O thread, once the inspection command was applied.
#include <mujoco/mujoco.h>

#include "net/msgpack_codec.h"
#include "urlab/ops/queries.h"

namespace urlab::net {

// The reply fields: contacts [{geom1, geom2, body1, body2 (names), pos, frame, normal, dist,
// force}], count, matched, truncated, time. Names come from `m` (immutable while running).
Json ContactsReply(const mjModel* m, const ops::ContactList& list);

}  // namespace urlab::net
