#pragma once
// GaitController: walks a legged robot with a floating base (a quadruped) at the twist its
// TwistController holds (vx forward, vy left, yaw rate; set by the viewer's Possess or the
// network's set_twist), acting only through the legs' actuators.
//
// The legs are found from the model (control/leg_kinematics.h): the chains of actuated hinges
// below the root body, each with a foot point; four legs, one per quadrant around the base. The
// standing pose (the scene's initial keyframe) gives each foot's nominal position under the base
// and the stance height. While the twist controller is attached it trots: a phase clock of
// `period` seconds, the diagonal pairs (front-left with rear-right, front-right with rear-left)
// swinging in turn for half a cycle each.
// - A stance foot moves in the base's level frame against the commanded motion: by -(v + w x p)
//   per second (v the planar velocity, w the yaw rate, p the foot's position), so it stays put
//   on the ground while the base moves as commanded; turning is this differential placement.
// - A swing foot travels from where it lifted to a Raibert-style landing point, the nominal
//   position plus half a stance of commanded motion plus `step_gain` * (measured - commanded
//   velocity), under a raised-cosine lift of `swing_height`.
// - Foot targets become joint targets by each leg's inverse kinematics; a joint PD (the scene's
//   kp, kv, torque_limit, as PdController, with the targets' own rate as the velocity target)
//   tracks them, plus, on stance legs, the torques J^T f of wanted ground reactions: the weight's
//   share with a PD on the stance height, roll and pitch; a pull toward the commanded planar
//   velocity and yaw rate (at most 0.3 of the normal force); and, while turning, the
//   torsional friction of the feet (geom friction[1] under condim 4 or 6) the turn must
//   overcome. Motors receive the torque; position servos the target shifted by torque / gain.
// The command is slewed (acceleration limits) so a step in the twist does not kick the legs.
// While detached it is a PdController on the active source's joint targets (a robot standing on
// its keyframe, or a client's targets); other actuators of the robot (not in a leg) always are.
//
// Threading contract
// - Main thread, before the engine runs: construction, Bind (throws Error when the legs cannot be
//   found), SetTwistSource.
// - Physics thread (step mutex held): ComputeAndApply, UseFrameGains.
// - Any thread: walking(), the PD gain setters and getters.
#include <atomic>
#include <memory>

#include "urlab/control/controllers.h"
#include "urlab/control/twist.h"

namespace urlab::control {

struct GaitSettings {
  double period = 0.4;         // s, one trot cycle (each foot swings for half of it)
  double swing_height = 0.07;  // m, foot lift at mid-swing
  double stance_height = 0;    // m, base above the feet; 0: from the standing pose
  double step_gain = 0.08;     // s, landing shift per m/s of velocity error (Raibert)
  int stand_key = -1;          // model keyframe of the standing pose; -1: qpos0
};

class GaitController : public PdController {
 public:
  GaitController(GaitSettings settings, PdGains gains);
  ~GaitController() override;

  // Binds and finds the legs (Error when there are not four legs of three or more hinges, one
  // per quadrant, below a root body with a free joint).
  void Bind(const mjModel* m, std::span<const int> actuator_ids) override;
  // The twist to walk at (the articulation's; must outlive the controller's use).
  void SetTwistSource(const TwistController* twist) { twist_ = twist; }
  void ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) override;
  // The gait starts a new cycle at the next step it walks (from the standing pose's feet).
  void Restart() override { walking_.store(false, std::memory_order_release); }

  const GaitSettings& settings() const { return settings_; }
  int num_legs() const;
  // The stance height in use (m, base above the feet).
  double stance_height() const;
  // True while the twist controller is attached and the gait runs.
  bool walking() const { return walking_.load(std::memory_order_acquire); }

 private:
  struct State;
  void Start(const mjModel* m, const mjData* d);
  void Walk(const mjModel* m, mjData* d, std::span<const double> targets);

  GaitSettings settings_;
  const TwistController* twist_ = nullptr;
  std::unique_ptr<State> state_;  // legs and the physics thread's gait state
  std::atomic<bool> walking_{false};
};

}  // namespace urlab::control
