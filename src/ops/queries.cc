// Queries (urlab/ops/queries.h).
#include "urlab/ops/queries.h"

#include <algorithm>

#include "ops/value_ranges.h"
#include "urlab/ops/error.h"
#include "urlab/world/names.h"

namespace urlab::ops {

namespace {

bool Pair(int a, int b, int want1, int want2) {
  const auto is = [](int id, int want) { return want < 0 || id == want; };
  return (is(a, want1) && is(b, want2)) || (is(a, want2) && is(b, want1));
}

}  // namespace

void CollectContacts(const mjModel* m, const mjData* d, const ContactFilter& filter,
                     int max_contacts, ContactList* out) {
  out->contacts.clear();
  out->matched = 0;
  out->time = d->time;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if (!Pair(m->geom_bodyid[c.geom1], m->geom_bodyid[c.geom2], filter.body1, filter.body2) ||
        !Pair(c.geom1, c.geom2, filter.geom1, filter.geom2)) {
      continue;
    }
    ++out->matched;
    if (static_cast<int>(out->contacts.size()) >= max_contacts) continue;
    Contact& r = out->contacts.emplace_back();
    r.geom1 = c.geom1;
    r.geom2 = c.geom2;
    std::copy_n(c.pos, 3, r.pos);
    std::copy_n(c.frame, 9, r.frame);
    r.dist = c.dist;
    mj_contactForce(m, d, i, r.force);
  }
}

ContactsQuery QueryContacts(world::Session& session, const ContactsRequest& request) {
  const mjModel* m = session.engine().model();
  CheckRange(request.max_contacts, "max_contacts");
  ContactFilter filter;
  const auto body = [m](const std::string& name) {
    if (name.empty()) return -1;
    const int id = mj_name2id(m, mjOBJ_BODY, name.c_str());
    if (id < 0) Fail("unknown_body", "no body '" + name + "' (full name, with its prefix)");
    return id;
  };
  const auto geom = [m](const std::string& name) {
    if (name.empty()) return -1;
    const int id = mj_name2id(m, mjOBJ_GEOM, name.c_str());
    if (id < 0) Fail("bad_value", "no geom '" + name + "' (full name, with its prefix)");
    return id;
  };
  filter.body1 = body(request.body1);
  filter.body2 = body(request.body2);
  filter.geom1 = geom(request.geom1);
  filter.geom2 = geom(request.geom2);
  ContactsQuery q;
  q.list = std::make_shared<ContactList>();
  q.seq = session.engine().Submit(physics::cmd::Inspect{
      [filter, max = request.max_contacts, list = q.list](const mjModel* model, const mjData* d) {
        CollectContacts(model, d, filter, max, list.get());
      },
      "get_contacts"});
  return q;
}

std::vector<KeyframeInfo> ListKeyframes(const world::Session& session) {
  const mjModel* m = session.engine().model();
  std::vector<KeyframeInfo> out;
  for (int k = 0; k < m->nkey; ++k) {
    const char* name = mj_id2name(m, mjOBJ_KEY, k);
    const world::Articulation* owner = name ? session.OwnerOf(name) : nullptr;
    out.push_back({world::ShortNameOf(m, mjOBJ_KEY, k, owner ? owner->prefix : ""),
                   owner ? owner->name() : "", name ? name : ""});
  }
  return out;
}

}  // namespace urlab::ops
