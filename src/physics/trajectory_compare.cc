#include "urlab/physics/trajectory_compare.h"

#include <cstring>
#include <memory>
#include <string>
#include <utility>

namespace urlab::physics {

std::string CompareSizes(const mjModel* a, const mjModel* b) {
  static constexpr std::pair<const char*, mjtSize mjModel::*> kSizes[] = {
      {"nq", &mjModel::nq},
      {"nv", &mjModel::nv},
      {"nu", &mjModel::nu},
      {"na", &mjModel::na},
      {"nbody", &mjModel::nbody},
      {"njnt", &mjModel::njnt},
      {"ngeom", &mjModel::ngeom},
      {"nsite", &mjModel::nsite},
      {"ncam", &mjModel::ncam},
      {"nlight", &mjModel::nlight},
      {"nmesh", &mjModel::nmesh},
      {"ntex", &mjModel::ntex},
      {"nmat", &mjModel::nmat},
      {"ntendon", &mjModel::ntendon},
      {"nsensor", &mjModel::nsensor},
      {"nkey", &mjModel::nkey},
      {"neq", &mjModel::neq},
      {"npair", &mjModel::npair},
      {"nexclude", &mjModel::nexclude},
      {"nmocap", &mjModel::nmocap},
      {"nskin", &mjModel::nskin},
      {"nhfield", &mjModel::nhfield},
      {"nwrap", &mjModel::nwrap},
      {"nnumeric", &mjModel::nnumeric},
      {"ntext", &mjModel::ntext},
      {"ntuple", &mjModel::ntuple},
      {"nsensordata", &mjModel::nsensordata},
      {"nuserdata", &mjModel::nuserdata},
      {"nmeshvert", &mjModel::nmeshvert},
      {"nmeshface", &mjModel::nmeshface}};
  for (const auto& [name, field] : kSizes) {
    if (a->*field != b->*field) {
      return std::string(name) + ": " + std::to_string(a->*field) + " vs " +
             std::to_string(b->*field);
    }
  }
  return "";
}

std::string CompareTrajectories(const mjModel* a, const mjModel* b, int steps) {
  if (a->nq != b->nq || a->nv != b->nv) return "nq/nv differ";
  std::unique_ptr<mjData, void (*)(mjData*)> da(mj_makeData(a), mj_deleteData);
  std::unique_ptr<mjData, void (*)(mjData*)> db(mj_makeData(b), mj_deleteData);
  for (int i = 0; i < steps; ++i) {
    mj_step(a, da.get());
    mj_step(b, db.get());
    if (std::memcmp(da->qpos, db->qpos, sizeof(mjtNum) * a->nq) != 0) {
      return "qpos differs after step " + std::to_string(i + 1);
    }
    if (std::memcmp(da->qvel, db->qvel, sizeof(mjtNum) * a->nv) != 0) {
      return "qvel differs after step " + std::to_string(i + 1);
    }
  }
  return "";
}

}  // namespace urlab::physics
