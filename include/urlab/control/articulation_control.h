#pragma once
// Per-articulation control: one command-frame channel per named source (network, UI, input,
// keyframe hold, replay), one source active at a time (the scene's global source, a
// per-articulation override, or the hold while holding a keyframe), the articulation's
// controller, and per-articulation keyframe reset. ControlSystem holds every articulation and
// the global control source and hooks them into a PhysicsEngine as its apply-controls step.
//
// Threading:
// - Main thread, before the engine runs: construction, SetController, ControlSystem::Add and
//   Install.
// - Any thread: PublishFrame/SetTarget/GetTarget/channel(), the source setters/getters,
//   HoldKeyframe/StopHold, ControlSystem::SetGlobalSource, ControlSystem::RequestKeyframeReset.
//   Frames are published whole (command_frame.h); the source switches are atomics; resets go
//   through the engine's command queue.
// - Physics thread (step mutex held): ApplyControls, ResetToKeyframe.
#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/control/command_frame.h"
#include "urlab/control/controller.h"
#include "urlab/control/twist.h"
#include "urlab/core/error.h"
#include "urlab/physics/delay_line.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/views.h"

namespace urlab::control {

class ArticulationControl {
 public:
  // Binds every actuator whose name starts with the bindings' prefix (sorted by id) and the
  // joints/actuators/mocap bodies the articulation owns. Uses a PassthroughController until
  // SetController is called.
  explicit ArticulationControl(const physics::ArticulationBindings& bindings);

  const std::string& prefix() const { return prefix_; }
  int num_actuators() const { return static_cast<int>(actuator_ids_.size()); }
  // MuJoCo ids of the actuators, ascending; targets are indexed the same way.
  const std::vector<int>& actuator_ids() const { return actuator_ids_; }
  // Index of an actuator by short name, -1 when absent.
  int IndexOf(std::string_view short_name) const;

  // Replaces the controller and binds it to this articulation's actuators (so poses can be added
  // right after). Main thread, while the engine does not run this articulation's controls.
  void SetController(std::unique_ptr<Controller> controller);
  // Typed convenience: SetController and return the controller.
  template <typename C>
  C& Use(std::unique_ptr<C> controller) {
    C& ref = *controller;
    SetController(std::move(controller));
    return ref;
  }
  Controller* controller() const { return controller_.get(); }
  // The twist controller (twist.h), applied after the controller every step while attached;
  // nullptr when the articulation has none (no free base). Main thread, before the engine runs.
  void SetTwistController(std::unique_ptr<TwistController> twist) { twist_ = std::move(twist); }
  TwistController* twist() const { return twist_.get(); }

  // The frame channel of a source (any thread: publish whole frames there).
  FrameChannel& channel(ControlSource source) const;
  // Publishes a whole frame to `source`: every target, optional gains (see FrameChannel). False
  // on a size mismatch. Any thread.
  bool PublishFrame(ControlSource source, std::span<const double> targets,
                    std::span<const double> kp = {}, std::span<const double> kv = {});
  // One target of a source's frame (the rest keep their values). Any thread. Returns false for
  // an unknown name/index.
  bool SetTarget(ControlSource source, int index, double value);
  bool SetTarget(ControlSource source, std::string_view short_name, double value);
  double GetTarget(ControlSource source, int index) const;

  // Per-articulation override of the global control source (std::nullopt: follow the global).
  void SetSourceOverride(std::optional<ControlSource> source);
  std::optional<ControlSource> source_override() const;
  // The source in effect given the global one (kHold while holding a keyframe).
  ControlSource EffectiveSource(ControlSource global) const;

  // Publishes the pose of model keyframe `key` (joint positions for position-target
  // controllers, the keyframe's ctrl otherwise) to the hold source and makes it the active one
  // until StopHold. Any thread. Throws Error for a bad key.
  void HoldKeyframe(int key);
  void HoldKeyframe(std::string_view name);
  // Starts every source but hold and replay at the pose of keyframe `key` (-1: the model's
  // reference configuration qpos0, zero controls), so that a robot whose source has sent
  // nothing yet keeps its initial pose instead of chasing zero targets. Any thread.
  void SeedTargets(int key);
  void StopHold() { holding_.store(false, std::memory_order_release); }
  bool holding() const { return holding_.load(std::memory_order_acquire); }

  // Control delay (physics/delay_line.h): the frame that reaches the controller in a step is the
  // one the active source held `delay` steps (plus jitter) earlier; each ApplyControls is one
  // tick. Physics thread, or the step mutex held (PhysicsEngine::WithLockedData). Setting a
  // spec restarts the line; ControlSystem restarts every line after a reset or restore. A
  // restarted line holds the frame the active source holds at that moment (the command in
  // effect) until the first delayed frame is released.
  void SetControlDelay(const physics::DelaySpec& spec, ControlSource global);
  const physics::DelaySpec& control_delay() const { return control_delay_.spec(); }
  void RestartControlDelay(ControlSource global);
  // The jitter drawn for the last step's command (0 without jitter).
  int last_control_jitter() const { return control_delay_.last_jitter(); }

  // Physics thread: feeds the active targets (through the control delay) to the controller,
  // which writes d->ctrl. Returns the frame it applied (valid until the next call).
  const CommandFrame& ApplyControls(const mjModel* m, mjData* d, ControlSource global);

  // Physics thread (use via ControlSystem::RequestKeyframeReset or PhysicsEngine::ResetWith):
  // writes this articulation's qpos/qvel/act/ctrl/mocap from keyframe `key` and clears its
  // warm start and applied forces; the rest of the scene is untouched. No mj_forward.
  void ResetToKeyframe(const mjModel* m, mjData* d, int key) const;

  // Finds keyframe `name` or prefix + `name`. Returns -1 when neither exists.
  int FindKeyframe(const mjModel* m, std::string_view name) const;

 private:
  // Targets that hold keyframe `key` (-1: qpos0): joint positions or the keyframe's ctrl.
  std::vector<double> PoseTargets(int key) const;

  std::string prefix_;
  const mjModel* model_;
  std::vector<int> actuator_ids_;
  std::vector<std::string> actuator_names_;  // short names
  // Owned state addresses, for per-articulation keyframe reset.
  std::vector<int> qpos_adrs_;
  std::vector<int> dof_adrs_;
  std::vector<int> act_adrs_;
  std::vector<int> mocap_ids_;
  std::vector<int> body_ids_;

  std::unique_ptr<Controller> controller_;
  std::unique_ptr<TwistController> twist_;
  std::array<std::unique_ptr<FrameChannel>, kNumControlSources> channels_;
  std::atomic<int> override_{-1};  // -1: none, else ControlSource
  std::atomic<bool> holding_{false};
  physics::DelayLine<CommandFrame> control_delay_;
};

class ControlSystem {
 public:
  ControlSystem() = default;
  ControlSystem(const ControlSystem&) = delete;
  ControlSystem& operator=(const ControlSystem&) = delete;

  // Global control source (any thread). Default kNetwork.
  void SetGlobalSource(ControlSource s) { global_.store(static_cast<int>(s)); }
  ControlSource global_source() const { return static_cast<ControlSource>(global_.load()); }

  // Adds an articulation (main thread, before Install). Returns it.
  ArticulationControl& Add(std::unique_ptr<ArticulationControl> articulation);
  // By prefix; nullptr when absent. Any thread once set up.
  ArticulationControl* Find(std::string_view prefix) const;
  const std::vector<std::unique_ptr<ArticulationControl>>& articulations() const { return all_; }

  // Registers ApplyControls of every articulation as the engine's apply-controls hook, and the
  // articulations as the engine's command layout (one group each, in Add order). Main thread,
  // before state subscriptions are made. The ControlSystem must outlive the engine's use of the
  // hook.
  void Install(physics::PhysicsEngine& engine);
  // Physics thread: what the hook does; `applied` (laid out as Install did), when given, receives
  // the frames applied.
  void ApplyControls(const mjModel* m, mjData* d, physics::AppliedCommands* applied = nullptr);

  // Queues a reset of one articulation to keyframe `key_name` (or prefix + name) on `engine`;
  // other articulations keep their state; returns the command's sequence number. Any thread.
  // Throws Error for unknown names.
  std::uint64_t RequestKeyframeReset(physics::PhysicsEngine& engine, std::string_view prefix,
                                     std::string_view key_name) const;

 private:
  std::atomic<int> global_{static_cast<int>(ControlSource::kNetwork)};
  std::vector<std::unique_ptr<ArticulationControl>> all_;
};

}  // namespace urlab::control
