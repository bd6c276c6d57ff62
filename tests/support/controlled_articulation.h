#pragma once
// An articulation of a test model under the control system, installed on its engine (before the
// engine runs), as a scene's articulation would be: tests publish command frames to it.
// Header-only: for the test executables that link urlab_control.
//
// Threading contract: construct on the test thread before the engine runs.
#include <memory>
#include <string>

#include "urlab/control/articulation_control.h"
#include "urlab/physics/engine.h"

namespace urlab::testing {

struct ControlledArticulation {
  // The articulation whose names start with `prefix` (the arm of physics/test_models.h: "arm_").
  explicit ControlledArticulation(physics::PhysicsEngine& engine,
                                  const std::string& prefix = "arm_") {
    engine.WithLockedData([&](mjModel* m, mjData* d) {
      articulation = &controls.Add(std::make_unique<control::ArticulationControl>(
          physics::ArticulationBindings(m, d, prefix)));
    });
    controls.Install(engine);
  }
  control::ArticulationControl& operator*() { return *articulation; }
  control::ArticulationControl* operator->() { return articulation; }

  control::ControlSystem controls;
  control::ArticulationControl* articulation = nullptr;
};

}  // namespace urlab::testing
