#include "render/frame_data.h"

#include <algorithm>
#include <cstddef>
#include <vector>

#include "urlab/physics/model.h"

namespace urlab::render {

namespace {

void CopyInto(const std::vector<mjtNum>& from, mjtNum* to, int n) {
  if (from.size() == static_cast<std::size_t>(n)) std::copy(from.begin(), from.end(), to);
}

}  // namespace

void CopyFrameToData(const mjModel* m, mjData* d, const physics::StateFrame& f) {
  d->time = f.time;
  CopyInto(f.qpos, d->qpos, m->nq);
  CopyInto(f.qvel, d->qvel, m->nv);
  CopyInto(f.act, d->act, m->na);
  CopyInto(f.ctrl, d->ctrl, m->nu);
  CopyInto(f.mocap_pos, d->mocap_pos, 3 * m->nmocap);
  CopyInto(f.mocap_quat, d->mocap_quat, 4 * m->nmocap);
  CopyInto(f.xfrc_applied, d->xfrc_applied, 6 * m->nbody);
  mj_kinematics(m, d);
  mj_comPos(m, d);
  mj_camlight(m, d);
  mj_flex(m, d);  // the flexes' vertex positions, which a flex is drawn from
  mj_tendon(m, d);
  mj_transmission(m, d);
}

void ReplaceModelValues(mjModel* m, const mjModel* source, const mjrContext* context) {
  const mjVisual vis = m->vis;
  physics::CopyModelValuesInPlace(m, source);
  m->vis = vis;
  if (!context) return;
  for (int i = 0; i < m->ntex; ++i) mjr_uploadTexture(m, context, i);
  for (int i = 0; i < m->nmesh; ++i) mjr_uploadMesh(m, context, i);
  for (int i = 0; i < m->nhfield; ++i) mjr_uploadHField(m, context, i);
}

}  // namespace urlab::render
