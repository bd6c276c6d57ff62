#include "urlab/control/twist.h"

#include <algorithm>
#include <cmath>

#include "urlab/core/error.h"

namespace urlab::control {

const char* ToString(TwistMode mode) {
  switch (mode) {
    case TwistMode::kPolicy:
      return "policy";
    case TwistMode::kGait:
      return "gait";
    case TwistMode::kHover:
      return "hover";
  }
  return "?";
}

std::optional<TwistMode> ParseTwistMode(std::string_view name) {
  for (TwistMode m : {TwistMode::kPolicy, TwistMode::kGait, TwistMode::kHover}) {
    if (name == ToString(m)) return m;
  }
  return std::nullopt;
}

void TwistController::Bind(const mjModel* m, int free_joint) {
  if (free_joint < 0 || free_joint >= m->njnt || m->jnt_type[free_joint] != mjJNT_FREE) {
    throw Error("TwistController: joint " + std::to_string(free_joint) +
                " is not a free joint (a twist drives a free base)");
  }
  root_ = m->jnt_bodyid[free_joint];
  dof_ = m->jnt_dofadr[free_joint];
  bodies_.clear();
  for (int b = root_; b < m->nbody; ++b) {  // a subtree's bodies follow its root
    int a = b;
    while (a > root_) a = m->body_parentid[a];
    if (a == root_) bodies_.push_back(b);
  }
}

Twist TwistController::SetTwist(Twist t) {
  const auto clamp = [](double v, double max) {
    return std::isfinite(v) ? std::clamp(v, -max, max) : 0.0;
  };
  t.vx = clamp(t.vx, settings_.max_vx);
  t.vy = clamp(t.vy, settings_.max_vy);
  t.yaw_rate = clamp(t.yaw_rate, settings_.max_yaw_rate);
  std::lock_guard lock(mutex_);
  twist_ = t;
  return t;
}

Twist TwistController::twist() const {
  std::lock_guard lock(mutex_);
  return twist_;
}

void TwistController::Attach(bool on) {
  if (on != attached()) {
    SetTwist({});
    SetActions(0);
  }
  attached_.store(on, std::memory_order_release);
}

void TwistController::Apply(const mjModel* m, mjData* d) {
  if (root_ < 0 || settings_.mode != TwistMode::kHover) return;
  mjtNum* row = d->xfrc_applied + 6 * root_;
  if (!attached()) {
    if (applied_) mju_zero(row, 6);
    applied_ = false;
    return;
  }
  applied_ = true;
  const Twist t = twist();
  const mjtNum* r = d->xmat + 9 * root_;  // row-major: the body's x axis is (r[0], r[3], r[6])
  const mjtNum yaw = std::atan2(r[3], r[0]);
  const mjtNum c = std::cos(yaw), s = std::sin(yaw);
  const mjtNum vx = c * t.vx - s * t.vy, vy = s * t.vx + c * t.vy;
  const mjtNum* v = d->qvel + dof_;  // free joint: world linear velocity, then local angular
  const mjtNum wz = r[6] * v[3] + r[7] * v[4] + r[8] * v[5];
  const mjtNum mass = m->body_subtreemass[root_];
  const mjtNum* com = d->subtree_com + 3 * root_;
  mjtNum izz = 0;
  for (int b : bodies_) {
    const mjtNum dx = d->xipos[3 * b] - com[0], dy = d->xipos[3 * b + 1] - com[1];
    izz += m->body_inertia[3 * b + 2] + m->body_mass[b] * (dx * dx + dy * dy);
  }
  // The force acts at the articulation's centre of mass (xfrc_applied acts at the root body's:
  // the lever between them is added as torque), so it neither pitches nor turns the robot.
  const mjtNum force[3] = {mass * settings_.linear_gain * (vx - v[0]),
                           mass * settings_.linear_gain * (vy - v[1]), 0};
  mjtNum lever[3], torque[3];
  mju_sub3(lever, com, d->xipos + 3 * root_);
  mju_cross(torque, lever, force);
  torque[2] += izz * settings_.yaw_gain * (t.yaw_rate - wz);
  mju_copy3(row, force);
  mju_copy3(row + 3, torque);
}

}  // namespace urlab::control
