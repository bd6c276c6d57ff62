#pragma once
// Possession (the description's Possess and MjTwistController input): while the viewer possesses
// an articulation, the driving keys (W/S forward and back, A/D left and right, Q/E yaw left and
// right) and a gamepad (GLFW's joystick API: left stick drives, right stick turns, buttons 0-9 are
// the action bits) set the articulation's twist controller, which clamps to the scene's maxima;
// the digit keys 0-9 hold action bits 0-9 (so the debug hotkeys 1-5 wait until the robot is
// released). A chase camera follows the robot from behind. The key tables are data, separate
// from what is done with them.
//
// Threading contract: main thread only (the twist controller it drives is any-thread).
#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <string>

#include "urlab/control/twist.h"

namespace urlab::viewer::internal {

// A driving key: which twist component it pushes, and which way.
struct DriveKey {
  int key;   // GLFW key code
  int axis;  // 0 vx, 1 vy, 2 yaw rate
  double sign;
};

// Why `twist` (an articulation's twist controller, null when it has none) cannot be possessed,
// "" when it can: it needs a free base that is the articulation's root (a child of the world)
// and something to move it: actuators, or the hover mode that pushes the base itself. A static
// prop, or a loose free body without actuators in a fixed scene, is not offered.
std::string WhyNotPossessable(const mjModel* m, const control::TwistController* twist,
                              int num_actuators);

class Possession {
 public:
  // Attaches `twist` (of articulation `articulation`) and drives it.
  void Possess(int articulation, control::TwistController* twist);
  // Detaches the twist controller; the robot stops being driven.
  void Release();
  bool active() const { return twist_ != nullptr; }
  int articulation() const { return articulation_; }

  // A key event while possessed; true when it was a driving or action key (consumed).
  bool OnKey(int key, int action);
  // Once a frame: combines the held keys with the first gamepad and sets the twist and actions.
  void Update();
  // The chase camera: tracks the root body, turning behind the robot's heading.
  void UpdateCamera(const mjData* d, mjvCamera* camera) const;
  // The last twist sent (after clamping) and action bits.
  control::Twist twist() const { return sent_; }
  std::uint32_t actions() const { return actions_; }

 private:
  control::TwistController* twist_ = nullptr;
  int articulation_ = -1;
  std::array<bool, 6> drive_held_{};  // per DriveKey
  std::uint32_t key_actions_ = 0;     // action bits held on the keyboard
  control::Twist sent_;
  std::uint32_t actions_ = 0;
};

}  // namespace urlab::viewer::internal
