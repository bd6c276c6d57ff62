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
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace urlab::control {

// Who drives an articulation's actuators. Each source has its own command frames per
// articulation; one source is active per articulation at a time.
enum class ControlSource {
  kNetwork,  // external clients (ZeroMQ)
  kUi,       // the viewer's panel sliders
  kInput,    // keyboard / gamepad input mapping
  kHold,     // "hold keyframe": the pose of a model keyframe
  kReplay,   // playback of a recording
};
inline constexpr int kNumControlSources = 5;

// "network", "ui", "input", "hold", "replay".
const char* ToString(ControlSource source);
// The inverse of ToString; std::nullopt for an unknown name.
std::optional<ControlSource> ParseControlSource(std::string_view name);

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
  // The range of the target this actuator takes, into range[0..1]; false when unbounded. With
  // position targets (PD, keyframe controllers) it is the joint's range when limited (narrowed to
  // the ctrlrange for a non-motor actuator, whose control is the target itself); with raw
  // controls, or without a joint, the ctrlrange when limited.
  bool TargetRange(bool position_targets, double range[2]) const;
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
  // Gains that arrived with the command frame of this step (one per binding, NaN: the
  // controller's own), or empty spans. Physics thread, right before ComputeAndApply; the spans
  // stay valid until ComputeAndApply returns. Controllers without gains ignore them.
  virtual void UseFrameGains(std::span<const double> /*kp*/, std::span<const double> /*kv*/) {}
  // The simulation was reset: a controller with a clock or memory (a keyframe sequence, a gait)
  // starts afresh at the next ComputeAndApply, as a new one would. Physics thread.
  virtual void Restart() {}
  // True when targets are joint positions (PD, keyframe); false when they are raw controls.
  virtual bool TargetsArePositions() const { return false; }

  const std::vector<ActuatorBinding>& bindings() const { return bindings_; }
  // Index of actuator `id` in bindings(), -1 when not bound.
  int IndexOfActuator(int id) const;

 protected:
  std::vector<ActuatorBinding> bindings_;
};

}  // namespace urlab::control
