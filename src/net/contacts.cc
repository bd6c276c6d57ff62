#include "net/contacts.h"

namespace urlab::net {

namespace {

bool Pair(int a, int b, int want1, int want2) {
  const auto is = [](int id, int want) { return want < 0 || id == want; };
  return (is(a, want1) && is(b, want2)) || (is(a, want2) && is(b, want1));
}

std::string Name(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
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
    ContactRecord r;
    r.geom1 = c.geom1;
    r.geom2 = c.geom2;
    std::copy_n(c.pos, 3, r.pos.begin());
    std::copy_n(c.frame, 9, r.frame.begin());
    r.dist = c.dist;
    mj_contactForce(m, d, i, r.force.data());
    out->contacts.push_back(r);
  }
}

Json ContactsReply(const mjModel* m, const ContactList& list) {
  Json contacts = Json::array();
  for (const ContactRecord& r : list.contacts) {
    contacts.push_back(Json{{"geom1", Name(m, mjOBJ_GEOM, r.geom1)},
                            {"geom2", Name(m, mjOBJ_GEOM, r.geom2)},
                            {"body1", Name(m, mjOBJ_BODY, m->geom_bodyid[r.geom1])},
                            {"body2", Name(m, mjOBJ_BODY, m->geom_bodyid[r.geom2])},
                            {"geom1_id", r.geom1},
                            {"geom2_id", r.geom2},
                            {"pos", r.pos},
                            {"frame", r.frame},
                            {"normal", {r.frame[0], r.frame[1], r.frame[2]}},
                            {"dist", r.dist},
                            {"force", r.force}});
  }
  const std::size_t n = list.contacts.size();
  return Json{{"contacts", std::move(contacts)},
              {"count", n},
              {"matched", list.matched},
              {"truncated", static_cast<std::size_t>(list.matched) > n},
              {"time", list.time}};
}

}  // namespace urlab::net
