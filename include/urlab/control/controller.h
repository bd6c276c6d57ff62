#pragma once
// Controller base: turns per-actuator targets into d->ctrl on the physics thread.
//
// Threading: Bind and configuration happen on the main thread before the physics loop uses the
// controller (or under PhysicsEngine::WithLockedData). ComputeAndApply runs on the physics thread
// with the step mutex held. Setters documented as "any thread" use atomics.
#include <mujoco/mujoco.h>

#include <atomic>
#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace urlab::control {

// Who drives an articulation's actuators: external clients over the network, or the UI.
enum class ControlSource { kNetwork, kUi };

// "network" / "ui".
const char* ToString(ControlSource source);

// A fixed-size array of values written by any thread and read by the physics thread, one
// std::atomic<double> per actuator (relaxed: each value is independent).
class AtomicValues {
 public:
  explicit AtomicValues(std::size_t n = 0, double initial = 0);
  std::size_t size() const { return n_; }
  void Set(std::size_t i, double v) { values_[i].store(v, std::memory_order_relaxed); }
  double Get(std::size_t i) const { return values_[i].load(std::memory_order_relaxed); }
  // Copies every value into out[0..size()).
  void CopyTo(std::span<double> out) const;

 private:
  std::size_t n_;
  std::unique_ptr<std::atomic<double>[]> values_;
};

// What a controller needs to know about one actuator, resolved once at Bind.
struct ActuatorBinding {
  int actuator_id = -1;
  // Joint transmission on a hinge or slide joint: the joint and its qpos/qvel addresses.
  int joint_id = -1;
  int qpos_adr = -1;
  int dof_adr = -1;
  bool joint_limited = false;
  double joint_range[2] = {0, 0};
  // Motor-type actuator (fixed gain, no bias): d->ctrl is a force scaled by gain * gear.
  bool motor = false;
  double gain = 1;  // gainprm[0]
  double gear = 1;  // gear[0]
  bool ctrl_limited = false;
  double ctrl_range[2] = {0, 0};

  bool has_joint() const { return qpos_adr >= 0; }
  // Clamps a position target to the joint range (when limited).
  double ClampToJoint(double q) const;
  // Clamps a control to the control range (when limited).
  double ClampCtrl(double u) const;
};

// Resolves the binding of actuator `id` of model `m`.
ActuatorBinding MakeActuatorBinding(const mjModel* m, int id);

// Abstract controller. Targets are indexed like bindings() (sorted by actuator id).
class Controller {
 public:
  virtual ~Controller() = default;
  // Binds to the given actuators (sorted by id). Main thread, before the loop uses it.
  virtual void Bind(const mjModel* m, std::span<const int> actuator_ids);
  // Writes d->ctrl for the bound actuators from targets[i] (one per binding). Physics thread.
  virtual void ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) = 0;
  // True when targets are joint positions (PD, keyframe); false when they are raw controls.
  virtual bool TargetsArePositions() const { return false; }

  const std::vector<ActuatorBinding>& bindings() const { return bindings_; }
  // Index of actuator `id` in bindings(), -1 when not bound.
  int IndexOfActuator(int id) const;

 protected:
  std::vector<ActuatorBinding> bindings_;
};

}  // namespace urlab::control
