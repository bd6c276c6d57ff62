// A compiled model's values copied into a running model of the same structure (model.h).
#include <cstdint>
#include <cstring>
#include <string>

#include "urlab/physics/model.h"

namespace urlab::physics {

namespace {

std::string QuotedName(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  return name && name[0] ? std::string("'") + name + "'" : "#" + std::to_string(id);
}

// The first element of `type` (of `count`) whose name differs, as "body 3 'a' is now 'b'".
std::string NameDifference(const mjModel* a, const mjModel* b, mjtObj type, const char* what,
                           int count) {
  for (int i = 0; i < count; ++i) {
    const char* na = mj_id2name(a, type, i);
    const char* nb = mj_id2name(b, type, i);
    if (std::strcmp(na ? na : "", nb ? nb : "") != 0) {
      return std::string(what) + " " + std::to_string(i) + " " + QuotedName(a, type, i) +
             " is now " + QuotedName(b, type, i);
    }
  }
  return {};
}

// The first row of `field` (`cols` values per element) that differs, as "joint 'a_knee' range".
template <typename T>
std::string RowDifference(const mjModel* a, const T* fa, const T* fb, int rows, int cols,
                          mjtObj type, const char* what, const char* field) {
  for (int i = 0; i < rows; ++i) {
    if (std::memcmp(fa + static_cast<std::size_t>(i) * cols,
                    fb + static_cast<std::size_t>(i) * cols, sizeof(T) * cols) != 0) {
      return std::string(what) + " " + QuotedName(a, type, i) + " " + field;
    }
  }
  return {};
}

}  // namespace

std::string InPlaceDifference(const mjModel* a, const mjModel* b) {
  // Sizes (MuJoCo's own list): the buffers and every address depend on them. Those of the name
  // and path buffers (and so the whole buffer's) come last, after the names themselves, so a
  // renamed element is named as such.
  const auto text_size = [](const char* name) {
    return std::strcmp(name, "nnames") == 0 || std::strcmp(name, "nnames_map") == 0 ||
           std::strcmp(name, "npaths") == 0 || std::strcmp(name, "nbuffer") == 0;
  };
  // The first size of the text ones (`text`) or of the others that differs, as "nbody 3 -> 4".
  const auto size_difference = [&](bool text) -> std::string {
#define X(name)                                                                                \
  if (text_size(#name) == text && a->name != b->name) {                                        \
    return std::string(#name " ") + std::to_string(static_cast<long long>(a->name)) + " -> " + \
           std::to_string(static_cast<long long>(b->name));                                    \
  }
    MJMODEL_SIZES
#undef X
    return {};
  };
  if (std::string d = size_difference(false); !d.empty()) return d;
  // Names: every element is bound, published and counted by its name.
  if (a->nnames != b->nnames ||
      std::memcmp(a->names, b->names, static_cast<std::size_t>(a->nnames)) != 0) {
    const struct {
      mjtObj type;
      const char* what;
      int count;
    } kinds[] = {{mjOBJ_BODY, "body", static_cast<int>(a->nbody)},
                 {mjOBJ_JOINT, "joint", static_cast<int>(a->njnt)},
                 {mjOBJ_GEOM, "geom", static_cast<int>(a->ngeom)},
                 {mjOBJ_SITE, "site", static_cast<int>(a->nsite)},
                 {mjOBJ_CAMERA, "camera", static_cast<int>(a->ncam)},
                 {mjOBJ_LIGHT, "light", static_cast<int>(a->nlight)},
                 {mjOBJ_ACTUATOR, "actuator", static_cast<int>(a->nu)},
                 {mjOBJ_SENSOR, "sensor", static_cast<int>(a->nsensor)},
                 {mjOBJ_TENDON, "tendon", static_cast<int>(a->ntendon)},
                 {mjOBJ_EQUALITY, "equality", static_cast<int>(a->neq)},
                 {mjOBJ_KEY, "keyframe", static_cast<int>(a->nkey)},
                 {mjOBJ_MESH, "mesh", static_cast<int>(a->nmesh)},
                 {mjOBJ_MATERIAL, "material", static_cast<int>(a->nmat)},
                 {mjOBJ_TEXTURE, "texture", static_cast<int>(a->ntex)}};
    for (const auto& k : kinds) {
      std::string d = NameDifference(a, b, k.type, k.what, k.count);
      if (!d.empty()) return d;
    }
    if (a->nnames != b->nnames) {
      return "nnames " + std::to_string(static_cast<long long>(a->nnames)) + " -> " +
             std::to_string(static_cast<long long>(b->nnames));
    }
    return "element names differ";
  }
  if (std::string d = size_difference(true); !d.empty()) return d;
  // What URLab resolved once when it bound the scene (views, bindings, controllers, layouts).
  const int nbody = static_cast<int>(a->nbody), njnt = static_cast<int>(a->njnt);
  const int nu = static_cast<int>(a->nu), nsensor = static_cast<int>(a->nsensor);
  const int ngeom = static_cast<int>(a->ngeom), nkey = static_cast<int>(a->nkey);
  const int nq = static_cast<int>(a->nq);
  std::string d;
  const auto body = [&](const auto* fa, const auto* fb, const char* field) {
    if (d.empty()) d = RowDifference(a, fa, fb, nbody, 1, mjOBJ_BODY, "body", field);
  };
  const auto joint = [&](const auto* fa, const auto* fb, int cols, const char* field) {
    if (d.empty()) d = RowDifference(a, fa, fb, njnt, cols, mjOBJ_JOINT, "joint", field);
  };
  const auto actuator = [&](const auto* fa, const auto* fb, int cols, const char* field) {
    if (d.empty()) d = RowDifference(a, fa, fb, nu, cols, mjOBJ_ACTUATOR, "actuator", field);
  };
  const auto sensor = [&](const auto* fa, const auto* fb, const char* field) {
    if (d.empty()) d = RowDifference(a, fa, fb, nsensor, 1, mjOBJ_SENSOR, "sensor", field);
  };
  body(a->body_parentid, b->body_parentid, "parent");
  body(a->body_mocapid, b->body_mocapid, "mocap");
  joint(a->jnt_type, b->jnt_type, 1, "type");
  joint(a->jnt_bodyid, b->jnt_bodyid, 1, "body");
  joint(a->jnt_qposadr, b->jnt_qposadr, 1, "qpos address");
  joint(a->jnt_dofadr, b->jnt_dofadr, 1, "dof address");
  joint(a->jnt_limited, b->jnt_limited, 1, "limited");
  joint(a->jnt_range, b->jnt_range, 2, "range");
  actuator(a->actuator_trntype, b->actuator_trntype, 1, "transmission type");
  actuator(a->actuator_trnid, b->actuator_trnid, 2, "transmission target");
  actuator(a->actuator_dyntype, b->actuator_dyntype, 1, "dynamics type");
  actuator(a->actuator_gaintype, b->actuator_gaintype, 1, "gain type");
  actuator(a->actuator_biastype, b->actuator_biastype, 1, "bias type");
  actuator(a->actuator_actadr, b->actuator_actadr, 1, "activation address");
  actuator(a->actuator_actnum, b->actuator_actnum, 1, "activation size");
  actuator(a->actuator_ctrllimited, b->actuator_ctrllimited, 1, "ctrllimited");
  actuator(a->actuator_ctrlrange, b->actuator_ctrlrange, 2, "ctrlrange");
  actuator(a->actuator_gear, b->actuator_gear, 1, "gear");
  sensor(a->sensor_type, b->sensor_type, "type");
  sensor(a->sensor_adr, b->sensor_adr, "address");
  sensor(a->sensor_dim, b->sensor_dim, "dimension");
  if (d.empty()) {
    d = RowDifference(a, a->geom_bodyid, b->geom_bodyid, ngeom, 1, mjOBJ_GEOM, "geom", "body");
  }
  if (!d.empty()) return d;
  // A motor's force is its control scaled by gain x gear (controllers convert with both).
  for (int i = 0; i < nu; ++i) {
    const bool motor = a->actuator_gaintype[i] == mjGAIN_FIXED &&
                       a->actuator_biastype[i] == mjBIAS_NONE &&
                       a->actuator_dyntype[i] == mjDYN_NONE;
    if (motor && a->actuator_gainprm[mjNGAIN * i] != b->actuator_gainprm[mjNGAIN * i]) {
      return "actuator " + QuotedName(a, mjOBJ_ACTUATOR, i) + " gain (a motor's)";
    }
  }
  // Keyframe poses: hold, keyframe and gait controllers took theirs when the scene was bound.
  d = RowDifference(a, a->key_qpos, b->key_qpos, nkey, nq, mjOBJ_KEY, "keyframe", "qpos");
  if (d.empty()) {
    d = RowDifference(a, a->key_ctrl, b->key_ctrl, nkey, nu, mjOBJ_KEY, "keyframe", "ctrl");
  }
  return d;
}

void CopyModelValuesInPlace(mjModel* dest, const mjModel* src) {
  // Only what differs is written: equal values (sizes, names, addresses) are never touched, so
  // another thread reading them (they never change while a model runs) does not race.
  const auto copy = [](void* to, const void* from, std::size_t bytes) {
    if (bytes && std::memcmp(to, from, bytes) != 0) std::memcpy(to, from, bytes);
  };
  copy(&dest->flg_gravcomp, &src->flg_gravcomp, sizeof(dest->flg_gravcomp));
  copy(&dest->flg_surfacevel, &src->flg_surfacevel, sizeof(dest->flg_surfacevel));
  copy(&dest->flg_adhesion, &src->flg_adhesion, sizeof(dest->flg_adhesion));
  copy(&dest->opt, &src->opt, sizeof(mjOption));
  copy(&dest->vis, &src->vis, sizeof(mjVisual));
  copy(&dest->stat, &src->stat, sizeof(mjStatistic));
  copy(&dest->signature, &src->signature, sizeof(dest->signature));
  {
    MJMODEL_POINTERS_PREAMBLE(src)
#define X(type, name, nr, nc) \
  copy(dest->name, src->name, \
       sizeof(type) * static_cast<std::size_t>(src->nr) * static_cast<std::size_t>(nc));
    MJMODEL_POINTERS
#undef X
  }
}

}  // namespace urlab::physics
