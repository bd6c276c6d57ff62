#pragma once
// Sensors and passive forces MuJoCo 2.2.2 cannot compute but the runtime can (also the 3.x
// sensors e_kinetic, e_potential, insidesite and contact, src/physics/sensors3x.h; gravity
// compensation: see GravityCompensationSpec below). MJCF written for MuJoCo 3.x uses
// `jointactuatorfrc` and `tendonactuatorfrc`, which the dialect bridge (mjcf/bridge.h) turns into
// 2.2.2 `<user>` sensors of the same name (objtype joint/tendon, dim 1, needstage acc). This
// module fills those sensors in from MuJoCo's own actuator results, through mjcb_sensor:
//
//   joint actuator force  = qfrc_actuator[jnt_dofadr[joint]]             (3.x jointactuatorfrc)
//   tendon actuator force = sum of actuator_force over actuators whose
//                           transmission is that tendon (gear not applied) (3.x tendonactuatorfrc)
//
// 3.x's `cutoff` is applied (as MuJoCo does for its own sensors). A physics::Model (model.h)
// owns its registration: it is the way to keep a model's extensions with it; the functions here
// are its mechanism (and are used directly by tests of single computations).
//
// Threading contract
// - mjcb_sensor and mjcb_passive are process-global. Registrations are kept in one registry, per
//   mjModel pointer: the callbacks (installed once, on the first non-empty registration, chaining
//   to callbacks installed before them) look up the state of the model MuJoCo passes them, so
//   any number of models step at once on their own threads (the physics thread, a re-simulation,
//   a renderer, tests), each with its own sensors and forces; a model not registered gets
//   nothing added.
// - The registry is guarded by a reader-writer lock: the callbacks take its shared side only
//   (held while they compute, so the state they read cannot go away under them);
//   RegisterSoftwareModel and the registration's destructor or assignment take the exclusive
//   side, from any thread. Neither side is held while another lock is taken, except that a
//   callback may run with its caller's locks held (the engine's step mutex): never register or
//   unregister while holding a lock a stepping thread takes around mj_step.
// - A registration unregisters its model when it dies, and only the registration it made (a
//   newer registration of the same pointer is left alone); the model must outlive it.
// - ApplySiteEqualities writes the mjModel: before any mjData made from it steps.
#include <mujoco/mujoco.h>

#include <map>
#include <span>
#include <string>
#include <vector>

namespace urlab::physics {

enum class SoftwareSensorKind {
  kJointActuatorForce,
  kTendonActuatorForce,
  kKineticEnergy,    // 3.x e_kinetic (mj_energyVel), velocity stage
  kPotentialEnergy,  // 3.x e_potential (mj_energyPos), position stage
  kInsideSite,       // 3.x insidesite, position stage
  kContact,          // 3.x contact (num slots of the data fields), acceleration stage
};

// A user sensor the runtime computes, named as in the model. `params`: the 3.x sensor's
// attributes for insidesite (site, objtype, objname) and contact (geom1/2, body1/2,
// subtree1/2, site, num, data, reduce); the user sensor's dimension must match.
struct SoftwareSensorSpec {
  std::string sensor_name;
  SoftwareSensorKind kind = SoftwareSensorKind::kJointActuatorForce;
  std::map<std::string, std::string> params;
};

// Keeps the sensors of one model registered; unregisters on destruction. Movable, not copyable.
class SoftwareSensorRegistration {
 public:
  SoftwareSensorRegistration() = default;
  SoftwareSensorRegistration(const mjModel* m, unsigned long generation)
      : model_(m), generation_(generation) {}
  SoftwareSensorRegistration(SoftwareSensorRegistration&& o) noexcept
      : model_(o.model_), generation_(o.generation_) {
    o.model_ = nullptr;
  }
  SoftwareSensorRegistration& operator=(SoftwareSensorRegistration&& o) noexcept;
  SoftwareSensorRegistration(const SoftwareSensorRegistration&) = delete;
  SoftwareSensorRegistration& operator=(const SoftwareSensorRegistration&) = delete;
  ~SoftwareSensorRegistration();

  const mjModel* model() const { return model_; }

 private:
  const mjModel* model_ = nullptr;
  unsigned long generation_ = 0;  // a newer registration of the same model is left alone
};

// Gravity compensation of one body (MuJoCo 3.x body `gravcomp`): a force gravcomp * mass *
// (-gravity) at the body's centre of mass, added to qfrc_passive through mjcb_passive exactly as
// 3.x's mj_gravcomp computes it (3.x routes the share of joints with `actuatorgravcomp` to
// qfrc_actuator instead; the sum of both is the same).
struct GravityCompensationSpec {
  std::string body_name;
  double gravcomp = 0;
};

// A body-based connect/weld that stands for a MuJoCo 3.x equality on two sites: its data is set
// from the sites' frames (connect: site1's position in body1, site2's in body2; weld: the same
// points and the relative orientation site1 * site2^-1), so the constraint holds the sites
// together as 3.x's does, wherever they are at qpos0.
struct SiteEqualitySpec {
  std::string equality, site1, site2;
};

// A tendon spring with a dead band (MuJoCo 3.x springlength="lo hi"): no force while the length is
// in [lo, hi], stiffness * (bound - length) outside, added to qfrc_passive through the tendon's
// moment arms (mjcb_passive). The 2.2.2 tendon carries stiffness 0.
struct DeadbandSpringSpec {
  std::string tendon_name;
  double stiffness = 0;
  double lo = 0, hi = 0;
};

// Everything the runtime computes for one model (its extensions): sensors (mjcb_sensor), passive
// forces (mjcb_passive) and the site equalities' data. One registry serves both callbacks.
struct SoftwareModelSpec {
  std::vector<SoftwareSensorSpec> sensors;
  std::vector<GravityCompensationSpec> gravcomp;
  std::vector<DeadbandSpringSpec> deadband_springs;
  std::vector<SiteEqualitySpec> site_equalities;  // applied by ApplySiteEqualities, not callbacks
  bool empty() const { return sensors.empty() && gravcomp.empty() && deadband_springs.empty(); }
};

// Registers what `spec` names for `m` (replacing an earlier registration of `m`) and installs the
// callbacks. Throws Error for a sensor as RegisterSoftwareSensors does, or a body that is not in
// the model. With an empty spec, registers nothing and returns an empty registration.
SoftwareSensorRegistration RegisterSoftwareModel(const mjModel* m, const SoftwareModelSpec& spec);

// Writes the data of the site equalities `spec` names into `m` (after compilation, before any
// mjData is made from it). Throws Error for names not in the model or an equality that is not
// a connect/weld between the sites' bodies.
void ApplySiteEqualities(mjModel* m, const SoftwareModelSpec& spec);

// Registers the sensors of `m` named in `specs` (replacing an earlier registration of `m`) and
// installs the callback. Throws Error when a name is not a user sensor of dimension 1 attached
// to a joint (hinge/slide) or tendon as its kind requires. With no specs, registers nothing and
// returns an empty registration. The model must outlive the registration.
SoftwareSensorRegistration RegisterSoftwareSensors(const mjModel* m,
                                                   std::span<const SoftwareSensorSpec> specs);

// Number of models currently registered (tests, diagnostics).
int RegisteredSoftwareSensorModels();

}  // namespace urlab::physics
