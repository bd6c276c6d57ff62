#include "viewer/possess.h"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <iterator>

namespace urlab::viewer::internal {

std::string WhyNotPossessable(const mjModel* m, const control::TwistController* twist,
                              int num_actuators) {
  if (!twist) return "no free base: nothing to possess";
  const int root = twist->root_body();
  if (root <= 0 || root >= m->nbody || m->body_parentid[root] != 0) {
    return "its free body is not its root: nothing to possess";
  }
  if (num_actuators == 0 && twist->settings().mode != control::TwistMode::kHover) {
    return "no actuators (and twist mode is not hover): nothing to possess";
  }
  return "";
}

namespace {

constexpr DriveKey kDriveKeys[] = {
    {GLFW_KEY_W, 0, +1}, {GLFW_KEY_S, 0, -1},  // forward / back
    {GLFW_KEY_A, 1, +1}, {GLFW_KEY_D, 1, -1},  // left / right
    {GLFW_KEY_Q, 2, +1}, {GLFW_KEY_E, 2, -1},  // turn left / right
};
static_assert(std::size(kDriveKeys) == 6);

// Gamepad sticks: which twist component each axis drives, and which way (GLFW's y axes point
// down). Stick values inside the dead zone count as zero.
struct StickAxis {
  int axis;  // GLFW_GAMEPAD_AXIS_*
  int twist_axis;
  double sign;
};
constexpr StickAxis kStickAxes[] = {
    {GLFW_GAMEPAD_AXIS_LEFT_Y, 0, -1},
    {GLFW_GAMEPAD_AXIS_LEFT_X, 1, -1},
    {GLFW_GAMEPAD_AXIS_RIGHT_X, 2, -1},
};
constexpr double kDeadZone = 0.15;

// Chase camera: distance behind the root body, pitch, and how fast it turns toward the heading
// (fraction of the gap closed per frame).
constexpr double kChaseDistance = 2.5;
constexpr double kChaseElevation = -20;
constexpr double kChaseTurn = 0.2;

}  // namespace

void Possession::Possess(int articulation, control::TwistController* twist) {
  Release();
  twist_ = twist;
  articulation_ = articulation;
  twist_->Attach(true);
}

void Possession::Release() {
  if (twist_) twist_->Attach(false);
  twist_ = nullptr;
  articulation_ = -1;
  drive_held_.fill(false);
  key_actions_ = 0;
  sent_ = {};
  actions_ = 0;
}

bool Possession::OnKey(int key, int action) {
  if (!active() || action == GLFW_REPEAT) return false;
  const bool down = action == GLFW_PRESS;
  for (std::size_t i = 0; i < std::size(kDriveKeys); ++i) {
    if (kDriveKeys[i].key == key) {
      drive_held_[i] = down;
      return true;
    }
  }
  if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) {
    const std::uint32_t bit = 1u << (key - GLFW_KEY_0);
    key_actions_ = down ? (key_actions_ | bit) : (key_actions_ & ~bit);
    return true;
  }
  return false;
}

void Possession::Update() {
  if (!active()) return;
  std::array<double, 3> axis{};  // -1..1 per twist component
  for (std::size_t i = 0; i < std::size(kDriveKeys); ++i) {
    if (drive_held_[i]) axis[static_cast<std::size_t>(kDriveKeys[i].axis)] += kDriveKeys[i].sign;
  }
  std::uint32_t actions = key_actions_;
  for (int jid = GLFW_JOYSTICK_1; jid <= GLFW_JOYSTICK_LAST; ++jid) {
    GLFWgamepadstate pad;
    if (!glfwJoystickIsGamepad(jid) || !glfwGetGamepadState(jid, &pad)) continue;
    for (const StickAxis& s : kStickAxes) {
      const double v = pad.axes[s.axis];
      if (std::abs(v) > kDeadZone) axis[static_cast<std::size_t>(s.twist_axis)] += s.sign * v;
    }
    for (int b = 0; b < control::kNumActionBits && b <= GLFW_GAMEPAD_BUTTON_LAST; ++b) {
      if (pad.buttons[b] == GLFW_PRESS) actions |= 1u << b;
    }
    break;  // the first gamepad drives
  }
  for (double& a : axis) a = std::clamp(a, -1.0, 1.0);
  const control::TwistSettings& max = twist_->settings();
  sent_ =
      twist_->SetTwist({axis[0] * max.max_vx, axis[1] * max.max_vy, axis[2] * max.max_yaw_rate});
  twist_->SetActions(actions);
  actions_ = twist_->actions();
}

void Possession::UpdateCamera(const mjData* d, mjvCamera* camera) const {
  if (!active()) return;
  const int root = twist_->root_body();
  if (camera->type != mjCAMERA_TRACKING || camera->trackbodyid != root) {
    camera->type = mjCAMERA_TRACKING;
    camera->trackbodyid = root;
    camera->distance = kChaseDistance;
    camera->elevation = kChaseElevation;
  }
  const mjtNum* r = d->xmat + 9 * root;
  const double heading = std::atan2(r[3], r[0]) * 180 / mjPI;  // the camera looks along it
  double gap = std::remainder(heading - camera->azimuth, 360.0);
  camera->azimuth += kChaseTurn * gap;
}

}  // namespace urlab::viewer::internal
