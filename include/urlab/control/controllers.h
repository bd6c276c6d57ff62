#pragma once
// The stock controllers: passthrough, PD servo and keyframe sequencer.
//
// Threading: construction, Bind, AddPose and option changes on the main thread before the loop
// uses the controller. Gain setters, Play/Stop and the status getters work from any thread
// (atomics). ComputeAndApply runs on the physics thread.
#include <atomic>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "urlab/control/controller.h"

namespace urlab::control {

// Writes each target straight into d->ctrl (clamped to ctrlrange when limited).
class PassthroughController : public Controller {
 public:
  void ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) override;
};

// Gains of one PD servo.
struct PdGains {
  double kp = 100;                                                // per unit of position error
  double kv = 10;                                                 // per unit of velocity
  double torque_limit = std::numeric_limits<double>::infinity();  // |joint torque| bound
};

// PD servo on joint positions. The target is clamped to the joint range. For motor-type
// actuators on a hinge/slide joint it computes the joint torque
//   tau = clamp(kp * (target - q) - kv * qdot, +-torque_limit)
// and writes ctrl = tau / (gain * gear) (clamped to ctrlrange), so the joint receives tau. Other
// actuators (position servos, tendon/site transmissions) receive the clamped target as ctrl.
class PdController : public Controller {
 public:
  explicit PdController(PdGains defaults = {});
  void Bind(const mjModel* m, std::span<const int> actuator_ids) override;
  void ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) override;
  bool TargetsArePositions() const override { return true; }
  // Frame gains override the per-binding gains for this step where they are not NaN.
  void UseFrameGains(std::span<const double> kp, std::span<const double> kv) override {
    frame_kp_ = kp;
    frame_kv_ = kv;
  }

  // Gains of binding i. Any thread (atomics); takes effect at the next step.
  void SetGains(int i, PdGains gains);
  PdGains gains(int i) const;
  const PdGains& default_gains() const { return defaults_; }

 protected:
  // The PD law for targets already resolved (used by subclasses), plus, when given, a joint
  // torque per binding added to the PD's (a motor receives it in its torque, before the limit;
  // a position servo as its target shifted by torque / (gain * gear)).
  void ApplyPositionTargets(const mjModel* m, mjData* d, std::span<const double> targets,
                            std::span<const double> feedforward = {});

 private:
  struct AtomicGains {
    std::atomic<double> kp, kv, limit;
  };
  PdGains defaults_;
  std::unique_ptr<AtomicGains[]> gains_;
  std::span<const double> frame_kp_, frame_kv_;  // physics thread: this step's frame gains
};

// One pose of a keyframe sequence: joint position targets for each binding.
struct KeyframePose {
  std::string name;
  std::vector<double> positions;  // one per binding (actuator order)
  double blend_time = 0.5;        // seconds to ease from the previous pose into this one
  double hold_time = 1.0;         // seconds to hold it afterwards
};

// Plays a sequence of poses through the PD law: after `start_delay`, blends (ease-in-out) from
// the pose at start into pose 0, holds it, blends into pose 1, ... With `loop` it then blends
// from the last pose back into pose 0 forever; otherwise it holds the last pose. Timing uses
// simulation time, so a restored state replays identically; a reset (time going backwards)
// restarts the sequence. While not playing it behaves like a PdController on incoming targets.
class KeyframeController : public PdController {
 public:
  struct Options {
    bool loop = false;
    bool autoplay = true;
    double start_delay = 0;
  };
  explicit KeyframeController(Options options, PdGains gains = {});
  KeyframeController() : KeyframeController(Options{}) {}

  // Adds a pose (main thread, before playing). Throws Error on a size mismatch with bindings().
  void AddPose(KeyframePose pose);
  // A pose from model keyframe `key` (qpos at each binding's joint; 0 for non-joint bindings).
  KeyframePose PoseFromModelKey(const mjModel* m, int key, double blend_time,
                                double hold_time) const;
  const std::vector<KeyframePose>& poses() const { return poses_; }

  // Any thread: (re)starts the sequence at the next step / stops it.
  void Play() { play_requested_.store(true, std::memory_order_release); }
  void Stop() { stop_requested_.store(true, std::memory_order_release); }
  bool playing() const { return playing_.load(std::memory_order_acquire); }
  // Pose being blended into or held, -1 before the first blend starts or when stopped.
  int current_pose() const { return current_pose_.load(std::memory_order_acquire); }
  // True while blending (false while holding or waiting).
  bool blending() const { return blending_.load(std::memory_order_acquire); }

  void Bind(const mjModel* m, std::span<const int> actuator_ids) override;
  void ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) override;
  // A playing sequence starts again from the pose the reset left (as autoplay does).
  void Restart() override;

  // Ease-in-out (smoothstep) of s in [0, 1].
  static double Ease(double s);

 private:
  void Start(const mjData* d);
  // Fills targets_ for simulation time `t` and updates the status atomics.
  void Evaluate(double t);

  Options options_;
  std::vector<KeyframePose> poses_;
  std::vector<double> start_pose_;  // physics thread
  std::vector<double> targets_;     // physics thread scratch
  double t0_ = 0;                   // physics thread: sim time of Start
  std::atomic<bool> play_requested_{false};
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> playing_{false};
  std::atomic<int> current_pose_{-1};
  std::atomic<bool> blending_{false};
};

}  // namespace urlab::control
