#pragma once
// InputMapping (the description's MjInputMapping): the scene's input bindings (a key, gamepad
// axis or gamepad button -> one actuator's target, value * scale) resolved against the session,
// and applied each frame through the articulation's `input` control source (a frame is published
// only when a mapped value changed, through ops::SetTargets like every path that sets targets;
// the source must be active for it to drive the robot, as with the panel's sliders and the `ui`
// source). Key names come from a table (letters, digits,
// arrows, Space...), separate from what is done with them. Mapped keys are consumed: they do not
// also trigger a hotkey.
//
// Threading contract: main thread only (publishing a target is any-thread).
#include <string>
#include <string_view>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/world/session.h"

namespace urlab::viewer::internal {

// The GLFW key code of a key name ("J", "7", "Space", "Up"; case-insensitive), -1 when unknown.
int KeyCode(std::string_view name);

class InputMapping {
 public:
  // Resolves every articulation's bindings; throws InputError at a binding's file:line for an
  // unknown key name or actuator.
  void Build(world::Session& session);
  bool empty() const { return bound_.empty(); }

  // A key event; true when the key is mapped (consumed).
  bool OnKey(int key, int action);
  // Once a frame: reads the first gamepad, sums each actuator's bindings and publishes the
  // targets that changed on the `input` source.
  void Update();

 private:
  struct Bound {
    control::ArticulationControl* control = nullptr;
    int index = -1;  // actuator index in the articulation
    int key = -1, axis = -1, button = -1;
    double scale = 1;
  };
  struct Target {
    control::ArticulationControl* control = nullptr;
    int index = -1;
    const std::string* articulation = nullptr;  // its name (the session's, which outlives this)
    double last = 0;                            // last published
  };
  world::Session* session_ = nullptr;
  std::vector<Bound> bound_;
  std::vector<int> target_of_;  // per bound: index into targets_
  std::vector<Target> targets_;
  std::vector<int> held_;  // mapped keys held down
};

}  // namespace urlab::viewer::internal
