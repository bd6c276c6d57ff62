#include "physics/sensors3x.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

constexpr const char* kFieldNames[7] = {"found", "force",  "torque", "dist",
                                        "pos",   "normal", "tangent"};
constexpr int kFieldSizes[7] = {1, 3, 3, 1, 3, 3, 3};

int Lookup(const mjModel* m, mjtObj type, const std::map<std::string, std::string>& a,
           const char* key, const std::string& what) {
  auto it = a.find(key);
  if (it == a.end()) return -1;
  const int id = mj_name2id(m, type, it->second.c_str());
  if (id < 0) throw Error(what + ": " + key + " '" + it->second + "' is not in the model");
  return id;
}

bool InSubtree(const mjModel* m, int body, int root) {
  for (int b = body; b >= 0; b = b == 0 ? -1 : m->body_parentid[b]) {
    if (b == root) return true;
  }
  return false;
}

// Whether the point `p` (global) is inside site `s`'s volume.
bool InsideSite(const mjModel* m, const mjData* d, int s, const mjtNum* p) {
  mjtNum rel[3], q[3];
  mju_sub3(rel, p, d->site_xpos + 3 * s);
  mju_mulMatTVec(q, d->site_xmat + 9 * s, rel, 3, 3);  // into the site's frame
  const mjtNum* size = m->site_size + 3 * s;
  switch (m->site_type[s]) {
    case mjGEOM_SPHERE:
      return mju_norm3(q) <= size[0];
    case mjGEOM_CAPSULE: {
      const mjtNum z = std::clamp(q[2], -size[1], size[1]);
      return std::hypot(q[0], q[1], q[2] - z) <= size[0];
    }
    case mjGEOM_ELLIPSOID:
      return q[0] * q[0] / (size[0] * size[0]) + q[1] * q[1] / (size[1] * size[1]) +
                 q[2] * q[2] / (size[2] * size[2]) <=
             1;
    case mjGEOM_CYLINDER:
      return std::hypot(q[0], q[1]) <= size[0] && std::abs(q[2]) <= size[1];
    case mjGEOM_BOX:
      return std::abs(q[0]) <= size[0] && std::abs(q[1]) <= size[1] && std::abs(q[2]) <= size[2];
    default:
      return false;
  }
}

// Whether geom `g` satisfies the criteria of side `k`.
bool SideMatches(const mjModel* m, const ContactSensor& s, int k, int g) {
  const int b = m->geom_bodyid[g];
  if (s.geom[k] >= 0 && s.geom[k] != g) return false;
  if (s.body[k] >= 0 && s.body[k] != b) return false;
  if (s.subtree[k] >= 0 && !InSubtree(m, b, s.subtree[k])) return false;
  return true;
}

bool HasSide(const ContactSensor& s, int k) {
  return s.geom[k] >= 0 || s.body[k] >= 0 || s.subtree[k] >= 0;
}

}  // namespace

int ContactSensor::SlotSize() const {
  int n = 0;
  for (int i = 0; i < 7; ++i) n += fields[i] ? kFieldSizes[i] : 0;
  return n;
}

InsideSiteSensor ParseInsideSite(const mjModel* m, const std::map<std::string, std::string>& a,
                                 const std::string& what) {
  InsideSiteSensor s;
  s.site = Lookup(m, mjOBJ_SITE, a, "site", what);
  if (s.site < 0) throw Error(what + ": needs a site");
  const std::string type = a.count("objtype") ? a.at("objtype") : "";
  const std::pair<const char*, mjtObj> types[] = {{"body", mjOBJ_BODY},
                                                  {"xbody", mjOBJ_XBODY},
                                                  {"geom", mjOBJ_GEOM},
                                                  {"site", mjOBJ_SITE},
                                                  {"camera", mjOBJ_CAMERA}};
  bool known = false;
  for (const auto& t : types) {
    if (type == t.first) {
      s.objtype = t.second;
      known = true;
    }
  }
  if (!known) throw Error(what + ": objtype '" + type + "' is not body/xbody/geom/site/camera");
  const mjtObj lookup = s.objtype == mjOBJ_XBODY ? mjOBJ_BODY : s.objtype;
  s.objid = Lookup(m, lookup, a, "objname", what);
  if (s.objid < 0) throw Error(what + ": needs objname");
  return s;
}

ContactSensor ParseContactSensor(const mjModel* m, const std::map<std::string, std::string>& a,
                                 const std::string& what) {
  ContactSensor s;
  s.geom[0] = Lookup(m, mjOBJ_GEOM, a, "geom1", what);
  s.geom[1] = Lookup(m, mjOBJ_GEOM, a, "geom2", what);
  s.body[0] = Lookup(m, mjOBJ_BODY, a, "body1", what);
  s.body[1] = Lookup(m, mjOBJ_BODY, a, "body2", what);
  s.subtree[0] = Lookup(m, mjOBJ_BODY, a, "subtree1", what);
  s.subtree[1] = Lookup(m, mjOBJ_BODY, a, "subtree2", what);
  s.site = Lookup(m, mjOBJ_SITE, a, "site", what);
  if (a.count("num")) s.num = std::atoi(a.at("num").c_str());
  if (s.num < 1) throw Error(what + ": num must be positive");
  const std::string reduce = a.count("reduce") ? a.at("reduce") : "none";
  if (reduce == "mindist") {
    s.reduce = ContactSensor::Reduce::kMinDist;
  } else if (reduce == "maxforce") {
    s.reduce = ContactSensor::Reduce::kMaxForce;
  } else if (reduce != "none") {
    throw Error(what + ": reduce '" + reduce + "' is not none/mindist/maxforce");
  }
  if (a.count("data")) {
    std::fill(std::begin(s.fields), std::end(s.fields), false);
    std::istringstream words(a.at("data"));
    int last = -1;
    for (std::string w; words >> w;) {
      const auto* f = std::find(std::begin(kFieldNames), std::end(kFieldNames), w);
      const int i = static_cast<int>(f - std::begin(kFieldNames));
      if (i >= 7 || i <= last) {
        throw Error(
            what + ": data '" + a.at("data") +
            "': fields are found, force, torque, dist, pos, normal, tangent, in that order");
      }
      s.fields[i] = true;
      last = i;
    }
  }
  return s;
}

mjtNum PotentialEnergy(const mjModel* m, const mjData* d) {
  mjtNum e = 0;
  if (!(m->opt.disableflags & mjDSBL_GRAVITY)) {
    for (int b = 1; b < m->nbody; ++b)
      e -= m->body_mass[b] * mju_dot3(m->opt.gravity, d->xipos + 3 * b);
  }
  if (m->opt.disableflags & mjDSBL_SPRING) return e;
  for (int j = 0; j < m->njnt; ++j) {
    const mjtNum k = m->jnt_stiffness[j];
    if (k == 0) continue;
    const int a = m->jnt_qposadr[j];
    const mjtNum* q = d->qpos + a;
    const mjtNum* q0 = m->qpos_spring + a;
    switch (m->jnt_type[j]) {
      case mjJNT_FREE: {
        mjtNum dif[3];
        mju_sub3(dif, q, q0);
        e += 0.5 * k * mju_dot3(dif, dif);
        q += 3;
        q0 += 3;
      }
        [[fallthrough]];
      case mjJNT_BALL: {
        mjtNum quat[4], dif[3];
        mju_copy4(quat, q);
        mju_normalize4(quat);
        mju_subQuat(dif, quat, q0);
        e += 0.5 * k * mju_dot3(dif, dif);
        break;
      }
      default:
        e += 0.5 * k * (*q - *q0) * (*q - *q0);
    }
  }
  for (int t = 0; t < m->ntendon; ++t) {
    const mjtNum k = m->tendon_stiffness[t];
    const mjtNum dl = d->ten_length[t] - m->tendon_lengthspring[t];
    e += 0.5 * k * dl * dl;
  }
  return e;
}

mjtNum KineticEnergy(const mjModel* m, const mjData* d) {
  std::vector<mjtNum> mv(static_cast<size_t>(m->nv));
  mj_mulM(m, d, mv.data(), d->qvel);
  return 0.5 * mju_dot(mv.data(), d->qvel, m->nv);
}

mjtNum InsideSiteValue(const mjModel* m, const mjData* d, const InsideSiteSensor& s) {
  const mjtNum* p = nullptr;
  switch (s.objtype) {
    case mjOBJ_BODY:
      p = d->xipos + 3 * s.objid;
      break;
    case mjOBJ_XBODY:
      p = d->xpos + 3 * s.objid;
      break;
    case mjOBJ_GEOM:
      p = d->geom_xpos + 3 * s.objid;
      break;
    case mjOBJ_SITE:
      p = d->site_xpos + 3 * s.objid;
      break;
    default:
      p = d->cam_xpos + 3 * s.objid;
      break;
  }
  return InsideSite(m, d, s.site, p) ? 1 : 0;
}

void ContactSensorValues(const mjModel* m, const mjData* d, const ContactSensor& s, mjtNum* out) {
  struct Match {
    int contact;
    bool flip;  // side 1 is the contact's geom2: the normal is reversed
    mjtNum force[6];
  };
  std::vector<Match> matches;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if (c.exclude != 0 || c.efc_address < 0) continue;  // filtered out: no force
    if (s.site >= 0 && !InsideSite(m, d, s.site, c.pos)) continue;
    bool flip = false;
    if (HasSide(s, 0) || HasSide(s, 1)) {
      const bool direct = SideMatches(m, s, 0, c.geom1) && SideMatches(m, s, 1, c.geom2);
      const bool swapped = SideMatches(m, s, 0, c.geom2) && SideMatches(m, s, 1, c.geom1);
      if (!direct && !swapped) continue;
      // Both subtrees the same body: the direction cannot be determined; keep the contact's.
      const bool same = s.subtree[0] >= 0 && s.subtree[0] == s.subtree[1];
      flip = !direct && !same;
    }
    Match mt{i, flip, {}};
    mj_contactForce(m, d, i, mt.force);
    matches.push_back(mt);
  }
  if (s.reduce == ContactSensor::Reduce::kMinDist) {
    std::stable_sort(matches.begin(), matches.end(), [&](const Match& a, const Match& b) {
      return d->contact[a.contact].dist < d->contact[b.contact].dist;
    });
  } else if (s.reduce == ContactSensor::Reduce::kMaxForce) {
    std::stable_sort(matches.begin(), matches.end(), [](const Match& a, const Match& b) {
      return mju_norm3(a.force) > mju_norm3(b.force);
    });
  }
  const int slot = s.SlotSize();
  mju_zero(out, s.num * slot);
  for (int k = 0; k < s.num && k < static_cast<int>(matches.size()); ++k) {
    const Match& mt = matches[static_cast<size_t>(k)];
    const mjContact& c = d->contact[mt.contact];
    const mjtNum sign = mt.flip ? -1 : 1;
    mjtNum* o = out + k * slot;
    if (s.fields[0]) *o++ = static_cast<mjtNum>(matches.size());
    if (s.fields[1]) o = std::copy(mt.force, mt.force + 3, o);
    if (s.fields[2]) o = std::copy(mt.force + 3, mt.force + 6, o);
    if (s.fields[3]) *o++ = c.dist;
    if (s.fields[4]) o = std::copy(c.pos, c.pos + 3, o);
    if (s.fields[5]) {
      for (int j = 0; j < 3; ++j) *o++ = sign * c.frame[j];
    }
    if (s.fields[6]) {
      for (int j = 0; j < 3; ++j) *o++ = sign * c.frame[3 + j];
    }
  }
}

}  // namespace urlab::physics
