#include "net/contacts.h"

#include <string>
#include <vector>

namespace urlab::net {

namespace {

std::string Name(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
}

Json Values(const double* v, int n) { return Json(std::vector<double>(v, v + n)); }

}  // namespace

Json ContactsReply(const mjModel* m, const ops::ContactList& list) {
  Json contacts = Json::array();
  for (const ops::Contact& r : list.contacts) {
    contacts.push_back(Json{{"geom1", Name(m, mjOBJ_GEOM, r.geom1)},
                            {"geom2", Name(m, mjOBJ_GEOM, r.geom2)},
                            {"body1", Name(m, mjOBJ_BODY, m->geom_bodyid[r.geom1])},
                            {"body2", Name(m, mjOBJ_BODY, m->geom_bodyid[r.geom2])},
                            {"geom1_id", r.geom1},
                            {"geom2_id", r.geom2},
                            {"pos", Values(r.pos, 3)},
                            {"frame", Values(r.frame, 9)},
                            {"normal", Values(r.frame, 3)},
                            {"dist", r.dist},
                            {"force", Values(r.force, 6)}});
  }
  const std::size_t n = list.contacts.size();
  return Json{{"contacts", std::move(contacts)},
              {"count", n},
              {"matched", list.matched},
              {"truncated", static_cast<std::size_t>(list.matched) > n},
              {"time", list.time}};
}

}  // namespace urlab::net
