#include "urlab/physics/trajectory_compare.h"

#include <cstring>
#include <memory>

namespace urlab::physics {

std::string CompareSizes(const mjModel* a, const mjModel* b) {
#define URLAB_CMP(field)    \
  if (a->field != b->field) \
    return #field ": " + std::to_string(a->field) + " vs " + std::to_string(b->field);
  URLAB_CMP(nq)
  URLAB_CMP(nv)
  URLAB_CMP(nu) URLAB_CMP(na) URLAB_CMP(nbody) URLAB_CMP(njnt) URLAB_CMP(ngeom) URLAB_CMP(nsite)
      URLAB_CMP(ncam) URLAB_CMP(nlight) URLAB_CMP(nmesh) URLAB_CMP(ntex) URLAB_CMP(nmat)
          URLAB_CMP(ntendon) URLAB_CMP(nsensor) URLAB_CMP(nkey) URLAB_CMP(neq) URLAB_CMP(npair)
              URLAB_CMP(nexclude) URLAB_CMP(nmocap) URLAB_CMP(nskin) URLAB_CMP(nhfield)
                  URLAB_CMP(nwrap) URLAB_CMP(nnumeric) URLAB_CMP(ntext) URLAB_CMP(ntuple)
                      URLAB_CMP(nsensordata) URLAB_CMP(nuserdata) URLAB_CMP(nmeshvert)
                          URLAB_CMP(nmeshface)
#undef URLAB_CMP
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
