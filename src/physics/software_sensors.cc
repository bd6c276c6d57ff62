#include "urlab/physics/software_sensors.h"

#include <mutex>
#include <shared_mutex>
#include <unordered_map>

#include "physics/sensors3x.h"
#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

struct Entry {
  int adr = 0;  // sensordata address
  SoftwareSensorKind kind = SoftwareSensorKind::kJointActuatorForce;
  int objid = 0;  // joint or tendon id
  int dof = 0;    // joint's dof address
  mjtNum cutoff = 0;
  int stage = mjSTAGE_ACC;
  InsideSiteSensor inside;
  ContactSensor contact;
};

struct GravcompEntry {
  int body = 0;
  mjtNum gravcomp = 0;
};

struct DeadbandEntry {
  int tendon = 0;
  mjtNum stiffness = 0, lo = 0, hi = 0;
};

struct Registered {
  unsigned long generation = 0;
  std::vector<Entry> entries;
  std::vector<GravcompEntry> gravcomp;
  std::vector<DeadbandEntry> deadband;
};

struct Registry {
  std::shared_mutex mutex;
  std::unordered_map<const mjModel*, Registered> models;
  unsigned long next_generation = 1;
  mjfSensor previous = nullptr;           // callback installed before ours
  mjfGeneric previous_passive = nullptr;  // likewise for mjcb_passive
};

Registry& TheRegistry() {
  static Registry* r = new Registry;  // never destroyed: the callback may run during exit
  return *r;
}

void Compute(const mjModel* m, mjData* d, const std::vector<Entry>& entries, int stage) {
  for (const Entry& e : entries) {
    if (e.stage != stage) continue;
    mjtNum v = 0;
    switch (e.kind) {
      case SoftwareSensorKind::kJointActuatorForce:
        v = d->qfrc_actuator[e.dof];
        break;
      case SoftwareSensorKind::kTendonActuatorForce:
        for (int i = 0; i < m->nu; ++i) {
          if (m->actuator_trntype[i] == mjTRN_TENDON && m->actuator_trnid[2 * i] == e.objid) {
            v += d->actuator_force[i];
          }
        }
        break;
      case SoftwareSensorKind::kKineticEnergy:
        v = KineticEnergy(m, d);
        break;
      case SoftwareSensorKind::kPotentialEnergy:
        v = PotentialEnergy(m, d);
        break;
      case SoftwareSensorKind::kInsideSite:
        v = InsideSiteValue(m, d, e.inside);
        break;
      case SoftwareSensorKind::kContact:
        ContactSensorValues(m, d, e.contact, d->sensordata + e.adr);
        continue;  // several values, no cutoff (3.x applies none to contact sensors)
    }
    if (e.cutoff > 0) v = mju_clip(v, -e.cutoff, e.cutoff);
    d->sensordata[e.adr] = v;
  }
}

// 3.x's mj_gravcomp: -gravity * mass * gravcomp at each body's centre of mass.
void Gravcomp(const mjModel* m, mjData* d, const std::vector<GravcompEntry>& entries) {
  if (entries.empty() || (m->opt.disableflags & mjDSBL_GRAVITY) || mju_norm3(m->opt.gravity) == 0) {
    return;
  }
  const mjtNum torque[3] = {0, 0, 0};
  for (const GravcompEntry& g : entries) {
    mjtNum force[3];
    mju_scl3(force, m->opt.gravity, -(m->body_mass[g.body] * g.gravcomp));
    mj_applyFT(m, d, force, torque, d->xipos + 3 * g.body, g.body, d->qfrc_passive);
  }
}

// 3.x's dead-band tendon spring: zero inside [lo, hi], stiffness * (bound - length) outside.
void Deadband(const mjModel* m, mjData* d, const std::vector<DeadbandEntry>& entries) {
  for (const DeadbandEntry& e : entries) {
    const mjtNum length = d->ten_length[e.tendon];
    mjtNum force = 0;
    if (length < e.lo) force = e.stiffness * (e.lo - length);
    if (length > e.hi) force = e.stiffness * (e.hi - length);
    if (force == 0) continue;
    // The tendon's Jacobian (its moment arms), kept sparse by the engine.
    const int t = e.tendon;
    const int adr = m->ten_J_rowadr[t];
    for (int k = 0; k < m->ten_J_rownnz[t]; ++k) {
      d->qfrc_passive[m->ten_J_colind[adr + k]] += d->ten_J[adr + k] * force;
    }
  }
}

void Passive(const mjModel* m, mjData* d, const Registered& r) {
  Gravcomp(m, d, r.gravcomp);
  Deadband(m, d, r.deadband);
}

void PassiveCallback(const mjModel* m, mjData* d) {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  if (r.previous_passive) r.previous_passive(m, d);
  auto it = r.models.find(m);
  if (it != r.models.end()) Passive(m, d, it->second);
}

void Callback(const mjModel* m, mjData* d, int stage) {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  if (r.previous) r.previous(m, d, stage);
  auto it = r.models.find(m);
  if (it != r.models.end()) Compute(m, d, it->second.entries, stage);
}

void InstallCallback() {
  static std::once_flag once;
  std::call_once(once, [] {
    Registry& r = TheRegistry();
    std::unique_lock lock(r.mutex);
    if (mjcb_sensor != &Callback) r.previous = mjcb_sensor;
    mjcb_sensor = &Callback;
    if (mjcb_passive != &PassiveCallback) r.previous_passive = mjcb_passive;
    mjcb_passive = &PassiveCallback;
  });
}

void Unregister(const mjModel* m, unsigned long generation) {
  if (!m) return;
  Registry& r = TheRegistry();
  std::unique_lock lock(r.mutex);
  auto it = r.models.find(m);
  if (it != r.models.end() && it->second.generation == generation) r.models.erase(it);
}

}  // namespace

SoftwareSensorRegistration& SoftwareSensorRegistration::operator=(
    SoftwareSensorRegistration&& o) noexcept {
  if (this != &o) {
    Unregister(model_, generation_);
    model_ = o.model_;
    generation_ = o.generation_;
    o.model_ = nullptr;
  }
  return *this;
}

SoftwareSensorRegistration::~SoftwareSensorRegistration() { Unregister(model_, generation_); }

SoftwareSensorRegistration RegisterSoftwareSensors(const mjModel* m,
                                                   std::span<const SoftwareSensorSpec> specs) {
  SoftwareModelSpec spec;
  spec.sensors.assign(specs.begin(), specs.end());
  return RegisterSoftwareModel(m, spec);
}

SoftwareSensorRegistration RegisterSoftwareModel(const mjModel* m, const SoftwareModelSpec& spec) {
  if (spec.empty()) return {};
  std::vector<Entry> entries;
  for (const SoftwareSensorSpec& s : spec.sensors) {
    const int id = mj_name2id(m, mjOBJ_SENSOR, s.sensor_name.c_str());
    const std::string what = "software sensor '" + s.sensor_name + "'";
    if (id < 0) throw Error(what + ": no sensor of that name in the model");
    Entry e;
    e.adr = m->sensor_adr[id];
    e.kind = s.kind;
    e.objid = m->sensor_objid[id];
    e.cutoff = m->sensor_cutoff[id];
    int dim = 1;
    if (s.kind == SoftwareSensorKind::kContact) {
      e.contact = ParseContactSensor(m, s.params, what);
      dim = e.contact.num * e.contact.SlotSize();
    }
    if (m->sensor_type[id] != mjSENS_USER || m->sensor_dim[id] != dim) {
      throw Error(what + ": must be a <user> sensor of dimension " + std::to_string(dim));
    }
    e.stage = s.kind == SoftwareSensorKind::kKineticEnergy     ? mjSTAGE_VEL
              : s.kind == SoftwareSensorKind::kPotentialEnergy ? mjSTAGE_POS
              : s.kind == SoftwareSensorKind::kInsideSite      ? mjSTAGE_POS
                                                               : mjSTAGE_ACC;
    if (m->sensor_needstage[id] != e.stage) {
      throw Error(what + ": the <user> sensor's needstage does not match its kind");
    }
    if (s.kind == SoftwareSensorKind::kInsideSite) {
      e.inside = ParseInsideSite(m, s.params, what);
    } else if (s.kind == SoftwareSensorKind::kJointActuatorForce) {
      if (m->sensor_objtype[id] != mjOBJ_JOINT) throw Error(what + ": must be attached to a joint");
      const int type = m->jnt_type[e.objid];
      if (type != mjJNT_HINGE && type != mjJNT_SLIDE) {
        throw Error(what + ": the joint must be a hinge or a slide");
      }
      e.dof = m->jnt_dofadr[e.objid];
    } else if (s.kind == SoftwareSensorKind::kTendonActuatorForce &&
               m->sensor_objtype[id] != mjOBJ_TENDON) {
      throw Error(what + ": must be attached to a tendon");
    }
    entries.push_back(e);
  }
  std::vector<GravcompEntry> gravcomp;
  for (const GravityCompensationSpec& g : spec.gravcomp) {
    const int id = mj_name2id(m, mjOBJ_BODY, g.body_name.c_str());
    if (id <= 0) throw Error("gravity compensation: no body '" + g.body_name + "' in the model");
    gravcomp.push_back({id, g.gravcomp});
  }
  std::vector<DeadbandEntry> deadband;
  for (const DeadbandSpringSpec& t : spec.deadband_springs) {
    const int id = mj_name2id(m, mjOBJ_TENDON, t.tendon_name.c_str());
    if (id < 0) throw Error("dead-band spring: no tendon '" + t.tendon_name + "' in the model");
    deadband.push_back({id, t.stiffness, t.lo, t.hi});
  }
  InstallCallback();
  Registry& r = TheRegistry();
  unsigned long generation = 0;
  {
    std::unique_lock lock(r.mutex);
    generation = r.next_generation++;
    r.models[m] =
        Registered{generation, std::move(entries), std::move(gravcomp), std::move(deadband)};
  }
  return SoftwareSensorRegistration(m, generation);
}

int RegisteredSoftwareSensorModels() {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  return static_cast<int>(r.models.size());
}

}  // namespace urlab::physics

namespace urlab::physics {

void ApplySiteEqualities(mjModel* m, const SoftwareModelSpec& spec) {
  for (const SiteEqualitySpec& e : spec.site_equalities) {
    const int id = mj_name2id(m, mjOBJ_EQUALITY, e.equality.c_str());
    const int s1 = mj_name2id(m, mjOBJ_SITE, e.site1.c_str());
    const int s2 = mj_name2id(m, mjOBJ_SITE, e.site2.c_str());
    const std::string what = "site equality '" + e.equality + "'";
    if (id < 0 || s1 < 0 || s2 < 0) throw Error(what + ": equality or site not in the model");
    const int type = m->eq_type[id];
    if ((type != mjEQ_CONNECT && type != mjEQ_WELD) || m->eq_obj1id[id] != m->site_bodyid[s1] ||
        m->eq_obj2id[id] != m->site_bodyid[s2]) {
      throw Error(what + ": must be a connect/weld between the bodies of its sites");
    }
    mjtNum* data = m->eq_data + static_cast<size_t>(id) * mjNEQDATA;
    if (type == mjEQ_CONNECT) {
      mju_copy3(data, m->site_pos + 3 * s1);      // anchor in body1
      mju_copy3(data + 3, m->site_pos + 3 * s2);  // anchor in body2
    } else {
      // 2.2.2's weld: data[0..2] the point in body2, data[3..5] the point in body1, data[6..9]
      // body2's orientation relative to body1: with site frames coinciding, q1^-1 q2 = qs1 qs2^-1.
      mju_copy3(data, m->site_pos + 3 * s2);
      mju_copy3(data + 3, m->site_pos + 3 * s1);
      mjtNum inv[4];
      mju_negQuat(inv, m->site_quat + 4 * s2);
      mju_mulQuat(data + 6, m->site_quat + 4 * s1, inv);
    }
  }
}

}  // namespace urlab::physics
