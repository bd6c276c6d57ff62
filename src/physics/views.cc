#include "urlab/physics/views.h"

#include <cstring>

namespace urlab::physics {

namespace {

const char* NameOf(const mjModel* m, mjtObj type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? n : "";
}

template <typename View>
void InitBase(View* v, mjModel* m, mjData* d, int i) {
  v->id = i;
  v->name = NameOf(m, View::kObjType, i);
  v->model = m;
  v->data = d;
}

// Activation address of actuator i (MuJoCo's actuator_actadr; -1 without activation).
int ActAdr(const mjModel* m, int i) { return m->actuator_actadr[i]; }

}  // namespace

int ElementCount(const mjModel* m, mjtObj type) {
  switch (type) {
    case mjOBJ_BODY:
      return m->nbody;
    case mjOBJ_GEOM:
      return m->ngeom;
    case mjOBJ_JOINT:
      return m->njnt;
    case mjOBJ_ACTUATOR:
      return m->nu;
    case mjOBJ_SENSOR:
      return m->nsensor;
    case mjOBJ_TENDON:
      return m->ntendon;
    case mjOBJ_SITE:
      return m->nsite;
    case mjOBJ_KEY:
      return m->nkey;
    default:
      return 0;
  }
}

int ResolveId(const mjModel* m, mjtObj type, std::string_view prefix, std::string_view name,
              int id_hint) {
  const std::string full = std::string(prefix) + std::string(name);
  // Path 1: the id, if in range and (when a name is known) still naming the same element; this
  // guards against stale ids from another compile.
  if (id_hint >= 0 && id_hint < ElementCount(m, type)) {
    if (name.empty() || full == NameOf(m, type, id_hint)) return id_hint;
  }
  // Path 2: the prefixed name.
  if (name.empty()) return -1;
  return mj_name2id(m, type, full.c_str());
}

void BodyView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  xpos = d->xpos + 3 * i;
  xquat = d->xquat + 4 * i;
  xfrc_applied = d->xfrc_applied + 6 * i;
  mass = m->body_mass + i;
  mocap_id = m->body_mocapid[i];
  parent_id = m->body_parentid[i];
}

std::vector<int> BodyView::Bodies() const {
  std::vector<int> out;
  for (int b = id + 1; b < model->nbody; ++b) {
    if (model->body_parentid[b] == id) out.push_back(b);
  }
  return out;
}

std::vector<int> BodyView::Geoms() const {
  std::vector<int> out;
  for (int k = 0; k < model->body_geomnum[id]; ++k) out.push_back(model->body_geomadr[id] + k);
  return out;
}

std::vector<int> BodyView::Joints() const {
  std::vector<int> out;
  for (int k = 0; k < model->body_jntnum[id]; ++k) out.push_back(model->body_jntadr[id] + k);
  return out;
}

void GeomView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  xpos = d->geom_xpos + 3 * i;
  xmat = d->geom_xmat + 9 * i;
  size = m->geom_size + 3 * i;
  type = m->geom_type + i;
  contype = m->geom_contype + i;
  conaffinity = m->geom_conaffinity + i;
  dataid = m->geom_dataid + i;
  body_id = m->geom_bodyid[i];
}

void JointView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  type = m->jnt_type[i];
  limited = m->jnt_limited[i] != 0;
  qpos_adr = m->jnt_qposadr[i];
  dof_adr = m->jnt_dofadr[i];
  switch (type) {
    case mjJNT_FREE:
      qpos_size = 7, dof_size = 6;
      break;
    case mjJNT_BALL:
      qpos_size = 4, dof_size = 3;
      break;
    default:
      qpos_size = 1, dof_size = 1;
      break;
  }
  qpos = d->qpos + qpos_adr;
  qvel = d->qvel + dof_adr;
  qacc = d->qacc + dof_adr;
  xanchor = d->xanchor + 3 * i;
  xaxis = d->xaxis + 3 * i;
  range = m->jnt_range + 2 * i;
  stiffness = m->jnt_stiffness + i;
  damping = m->dof_damping + dof_adr;
}

void ActuatorView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  ctrl = d->ctrl + i;
  force = d->actuator_force + i;
  length = d->actuator_length + i;
  ctrlrange = m->actuator_ctrlrange + 2 * i;
  gainprm = m->actuator_gainprm + mjNGAIN * i;
  biasprm = m->actuator_biasprm + mjNBIAS * i;
  gear = m->actuator_gear + 6 * i;
  act_adr = ActAdr(m, i);
  act = act_adr >= 0 ? d->act + act_adr : nullptr;
  trntype = m->actuator_trntype[i];
  trnid = m->actuator_trnid[2 * i];
}

void SensorView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  adr = m->sensor_adr[i];
  dim = m->sensor_dim[i];
  type = m->sensor_type[i];
  values = d->sensordata + adr;
}

void TendonView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  length = d->ten_length + i;
  velocity = d->ten_velocity + i;
  stiffness = m->tendon_stiffness + i;
  damping = m->tendon_damping + i;
  range = m->tendon_range + 2 * i;
}

void SiteView::Init(mjModel* m, mjData* d, int i) {
  InitBase(this, m, d, i);
  xpos = d->site_xpos + 3 * i;
  xmat = d->site_xmat + 9 * i;
  size = m->site_size + 3 * i;
  type = m->site_type + i;
  body_id = m->site_bodyid[i];
}

template <typename View>
void ElementSet<View>::Build(mjModel* m, mjData* d, std::string_view prefix) {
  views_.clear();
  short_names_.clear();
  by_name_.clear();
  const int n = ElementCount(m, View::kObjType);
  by_id_.assign(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    const std::string_view full = NameOf(m, View::kObjType, i);
    if (full.empty() || !full.starts_with(prefix)) continue;
    View v;
    v.Init(m, d, i);
    by_id_[static_cast<std::size_t>(i)] = static_cast<int>(views_.size());
    std::string short_name(full.substr(prefix.size()));
    by_name_.emplace(short_name, static_cast<int>(views_.size()));
    short_names_.push_back(std::move(short_name));
    views_.push_back(std::move(v));
  }
}

template class ElementSet<BodyView>;
template class ElementSet<GeomView>;
template class ElementSet<JointView>;
template class ElementSet<ActuatorView>;
template class ElementSet<SensorView>;
template class ElementSet<TendonView>;
template class ElementSet<SiteView>;

ArticulationBindings::ArticulationBindings(mjModel* m, mjData* d, std::string prefix)
    : prefix_(std::move(prefix)), model_(m), data_(d) {
  if (!m || !d) throw BindError("ArticulationBindings needs a model and data");
  bodies_.Build(m, d, prefix_);
  geoms_.Build(m, d, prefix_);
  joints_.Build(m, d, prefix_);
  actuators_.Build(m, d, prefix_);
  sensors_.Build(m, d, prefix_);
  tendons_.Build(m, d, prefix_);
  sites_.Build(m, d, prefix_);
  for (int k = 0; k < m->nkey; ++k) {
    if (std::string_view(NameOf(m, mjOBJ_KEY, k)).starts_with(prefix_)) keyframes_.push_back(k);
  }
}

}  // namespace urlab::physics
