#include "urlab/physics/software_sensors.h"

#include <mutex>
#include <shared_mutex>
#include <unordered_map>

#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

struct Entry {
  int adr = 0;  // sensordata address
  SoftwareSensorKind kind = SoftwareSensorKind::kJointActuatorForce;
  int objid = 0;  // joint or tendon id
  int dof = 0;    // joint's dof address
  mjtNum cutoff = 0;
};

struct Registered {
  unsigned long generation = 0;
  std::vector<Entry> entries;
};

struct Registry {
  std::shared_mutex mutex;
  std::unordered_map<const mjModel*, Registered> models;
  unsigned long next_generation = 1;
  mjfSensor previous = nullptr;  // callback installed before ours
};

Registry& TheRegistry() {
  static Registry* r = new Registry;  // never destroyed: the callback may run during exit
  return *r;
}

void Compute(const mjModel* m, mjData* d, const std::vector<Entry>& entries) {
  for (const Entry& e : entries) {
    mjtNum v = 0;
    if (e.kind == SoftwareSensorKind::kJointActuatorForce) {
      v = d->qfrc_actuator[e.dof];
    } else {
      for (int i = 0; i < m->nu; ++i) {
        if (m->actuator_trntype[i] == mjTRN_TENDON && m->actuator_trnid[2 * i] == e.objid) {
          v += d->actuator_force[i];
        }
      }
    }
    if (e.cutoff > 0) v = mju_clip(v, -e.cutoff, e.cutoff);
    d->sensordata[e.adr] = v;
  }
}

void Callback(const mjModel* m, mjData* d, int stage) {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  if (r.previous) r.previous(m, d, stage);
  if (stage != mjSTAGE_ACC) return;
  auto it = r.models.find(m);
  if (it != r.models.end()) Compute(m, d, it->second.entries);
}

void InstallCallback() {
  static std::once_flag once;
  std::call_once(once, [] {
    Registry& r = TheRegistry();
    std::unique_lock lock(r.mutex);
    if (mjcb_sensor != &Callback) r.previous = mjcb_sensor;
    mjcb_sensor = &Callback;
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
  if (specs.empty()) return {};
  std::vector<Entry> entries;
  for (const SoftwareSensorSpec& s : specs) {
    const int id = mj_name2id(m, mjOBJ_SENSOR, s.sensor_name.c_str());
    const std::string what = "software sensor '" + s.sensor_name + "'";
    if (id < 0) throw Error(what + ": no sensor of that name in the model");
    if (m->sensor_type[id] != mjSENS_USER || m->sensor_dim[id] != 1) {
      throw Error(what + ": must be a <user> sensor of dimension 1");
    }
    Entry e;
    e.adr = m->sensor_adr[id];
    e.kind = s.kind;
    e.objid = m->sensor_objid[id];
    e.cutoff = m->sensor_cutoff[id];
    if (s.kind == SoftwareSensorKind::kJointActuatorForce) {
      if (m->sensor_objtype[id] != mjOBJ_JOINT) throw Error(what + ": must be attached to a joint");
      const int type = m->jnt_type[e.objid];
      if (type != mjJNT_HINGE && type != mjJNT_SLIDE) {
        throw Error(what + ": the joint must be a hinge or a slide");
      }
      e.dof = m->jnt_dofadr[e.objid];
    } else if (m->sensor_objtype[id] != mjOBJ_TENDON) {
      throw Error(what + ": must be attached to a tendon");
    }
    entries.push_back(e);
  }
  InstallCallback();
  Registry& r = TheRegistry();
  unsigned long generation = 0;
  {
    std::unique_lock lock(r.mutex);
    generation = r.next_generation++;
    r.models[m] = Registered{generation, std::move(entries)};
  }
  return SoftwareSensorRegistration(m, generation);
}

int RegisteredSoftwareSensorModels() {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  return static_cast<int>(r.models.size());
}

void ComputeSoftwareSensors(const mjModel* m, mjData* d) {
  Registry& r = TheRegistry();
  std::shared_lock lock(r.mutex);
  auto it = r.models.find(m);
  if (it != r.models.end()) Compute(m, d, it->second.entries);
}

}  // namespace urlab::physics
