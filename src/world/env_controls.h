#pragma once
// EnvControls: the scene's controllers for one environment of a batch (world::BatchSubsystem),
// so that a batch's actions are what a client of the running scene sends: joint targets under
// a PD, keyframe or gait controller, raw controls under none. Each articulation gets a fresh
// controller built from its scene description by the same factory the session uses
// (InstallController, InstallTwist), bound to the same actuators; the twist controller stays
// detached (a gait controller is then a PD on joint targets), and no control source, hold or
// frame gains apply: the environment's actions are the targets. Actuators no articulation owns
// take their action as the control.
//
// Threading contract
// - Main thread, before the batch uses it: construction (reads the session's articulations and
//   model), TargetBounds.
// - The thread stepping the environment (one at a time): Apply, Restart, and the PD controllers'
//   gains through pd() (a domain randomisation draw at the environment's reset).
#include <mujoco/mujoco.h>

#include <memory>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/control/controllers.h"
#include "urlab/physics/batch.h"
#include "urlab/world/session.h"

namespace urlab::world {

class EnvControls : public physics::ControlLaw {
 public:
  // Builds every articulation's controller against the session's model. Throws what
  // InstallController throws (the session has built the same ones already, so it does not).
  explicit EnvControls(const Session& session);

  // True when any articulation's controller does more than pass its targets through (a batch
  // needs no control law otherwise: the actions are the controls).
  static bool Needed(const Session& session);

  // The actions' bounds, actuator order (`low` and `high` hold the ctrlranges, nu each): each
  // actuator a controller binds takes the range of its targets instead
  // (control::ActuatorBinding::TargetRange: the joint's range under a PD; -inf / +inf without).
  void TargetBounds(std::vector<double>* low, std::vector<double>* high) const;

  void Apply(const mjModel* m, mjData* d) override;
  void Restart() override;

  // Articulation i's PD controller (nullptr when its controller is not a PD), for the gains a
  // randomisation draws.
  control::PdController* pd(std::size_t articulation) const;

 private:
  std::vector<std::unique_ptr<control::ArticulationControl>> controls_;
  std::vector<std::vector<double>> targets_;  // scratch: each articulation's targets
  std::vector<double> actions_;               // scratch: the actions as ctrl held them
};

}  // namespace urlab::world
