#include "urlab/control/gait.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "control/leg_kinematics.h"
#include "urlab/core/error.h"

namespace urlab::control {

namespace {

// Command slew limits: a step in the twist reaches the legs over a few tenths of a second.
constexpr double kLinearAccel = 1.5;  // m/s^2
constexpr double kYawAccel = 3.0;     // rad/s^2
// Time constant of the measured velocity the landing points use (s).
constexpr double kVelocityFilter = 0.1;
// Stance force feedback, per kg of robot: base height (1/s^2, 1/s) and attitude (1/s^2 m^2-ish
// so that a 15 kg robot gets about 45 N m/rad), added to the weight's share.
constexpr double kHeightStiffness = 40, kHeightDamping = 4;
constexpr double kAttitudeStiffness = 3, kAttitudeDamping = 0.2;
// Planar velocity and yaw rate feedback through the stance feet (1/s), and the share of the
// normal force those horizontal forces may use (below the usual friction coefficients).
constexpr double kVelocityGain = 2, kYawGain = 4, kFrictionUse = 0.3;
// How far a landing point may move from its nominal position, as a fraction of the stance height.
constexpr double kMaxStepFraction = 0.6;

double Smooth(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

double Slew(double from, double to, double max_step) {
  return from + std::clamp(to - from, -max_step, max_step);
}

}  // namespace

struct GaitController::State {
  struct LegState {
    double p[3] = {0, 0, 0};     // foot target, base level frame
    double lift[3] = {0, 0, 0};  // where the current swing started
    bool swinging = false;
    std::vector<double> q;  // inverse kinematics, warm start
  };
  std::vector<legs::Leg> legs;
  std::vector<double> phase_offset;  // 0 or 0.5 (diagonal pairs)
  std::vector<LegState> leg_state;
  int root = -1, free_qpos = -1, free_dof = -1;
  std::vector<int> bodies;  // the root's subtree
  double mass = 0, height = 0;
  double t0 = 0;
  double cmd[3] = {0, 0, 0};  // slewed vx, vy, yaw rate
  double vel[2] = {0, 0};     // filtered planar velocity, heading frame
  std::vector<double> targets, feedforward, jac;
};

GaitController::GaitController(GaitSettings settings, PdGains gains)
    : PdController(gains), settings_(settings), state_(std::make_unique<State>()) {}

GaitController::~GaitController() = default;

int GaitController::num_legs() const { return static_cast<int>(state_->legs.size()); }
double GaitController::stance_height() const { return state_->height; }

void GaitController::Bind(const mjModel* m, std::span<const int> actuator_ids) {
  PdController::Bind(m, actuator_ids);
  State& s = *state_;
  s = State{};
  int root = -1;
  for (const ActuatorBinding& b : bindings_) {
    if (b.joint_id >= 0) {
      root = m->body_rootid[m->jnt_bodyid[b.joint_id]];
      break;
    }
  }
  if (root < 0) throw Error("gait: the robot has no actuated joints");
  const int key = settings_.stand_key;
  if (key >= m->nkey) throw Error("gait: standing keyframe id out of range");
  const mjtNum* stand = key >= 0 ? m->key_qpos + static_cast<std::size_t>(key) * m->nq : m->qpos0;
  s.legs = legs::FindLegs(m, root, bindings_, stand);
  // One leg per quadrant around the base: front/rear by x, left/right by y of the hip.
  std::array<int, 4> quadrant = {-1, -1, -1, -1};  // FL, FR, RL, RR
  for (std::size_t i = 0; i < s.legs.size(); ++i) {
    const double* h = s.legs[i].hip;
    const int k = (h[0] > 0 ? 0 : 2) + (h[1] > 0 ? 0 : 1);
    if (s.legs.size() == 4 && quadrant[static_cast<std::size_t>(k)] < 0) {
      quadrant[static_cast<std::size_t>(k)] = static_cast<int>(i);
    }
  }
  if (s.legs.size() != 4 || std::count(quadrant.begin(), quadrant.end(), -1) > 0) {
    std::string names;
    for (const legs::Leg& l : s.legs) names += (names.empty() ? "" : ", ") + l.name;
    throw Error("gait: a trot needs four legs, one at each corner of the base; found " +
                std::to_string(s.legs.size()) + (names.empty() ? "" : " (" + names + ")"));
  }
  s.phase_offset.assign(4, 0);
  s.phase_offset[static_cast<std::size_t>(quadrant[1])] = 0.5;  // FR with RL
  s.phase_offset[static_cast<std::size_t>(quadrant[2])] = 0.5;
  s.leg_state.resize(4);
  s.root = root;
  const int free_joint = m->body_jntadr[root];
  s.free_qpos = m->jnt_qposadr[free_joint];
  s.free_dof = m->jnt_dofadr[free_joint];
  s.mass = m->body_subtreemass[root];
  for (int b = root; b < m->nbody; ++b) {  // a subtree's bodies follow its root
    int a = b;
    while (a > root) a = m->body_parentid[a];
    if (a == root) s.bodies.push_back(b);
  }
  if (settings_.stance_height > 0) {
    s.height = settings_.stance_height;
  } else {
    for (const legs::Leg& l : s.legs) s.height -= l.stand[2] / 4;
  }
  if (!(s.height > 0)) {
    throw Error("gait: the feet of the standing pose are not below the base");
  }
  s.targets.assign(bindings_.size(), 0);
  s.feedforward.assign(bindings_.size(), 0);
  std::size_t most = 0;
  for (const legs::Leg& l : s.legs) most = std::max(most, l.joints.size());
  s.jac.assign(3 * most, 0);
}

void GaitController::Start(const mjModel*, const mjData* d) {
  State& s = *state_;
  s.t0 = d->time;
  for (std::size_t i = 0; i < s.legs.size(); ++i) {
    State::LegState& ls = s.leg_state[i];
    mju_copy3(ls.p, s.legs[i].stand);
    ls.p[2] = -s.height;
    ls.swinging = false;
    ls.q = s.legs[i].stand_q;
  }
  s.cmd[0] = s.cmd[1] = s.cmd[2] = 0;
  s.vel[0] = s.vel[1] = 0;
  walking_.store(true, std::memory_order_release);
}

void GaitController::ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) {
  if (!twist_ || !twist_->attached() || state_->legs.empty()) {
    walking_.store(false, std::memory_order_release);
    return ApplyPositionTargets(m, d, targets);
  }
  if (!walking() || d->time < state_->t0) Start(m, d);  // attached, or a reset went back
  Walk(m, d, targets);
}

void GaitController::Walk(const mjModel* m, mjData* d, std::span<const double> targets) {
  State& s = *state_;
  const double dt = m->opt.timestep;
  const double g = -m->opt.gravity[2] > 0 ? -m->opt.gravity[2] : 9.81;

  // The command, slewed.
  const Twist tw = twist_->twist();
  s.cmd[0] = Slew(s.cmd[0], tw.vx, kLinearAccel * dt);
  s.cmd[1] = Slew(s.cmd[1], tw.vy, kLinearAccel * dt);
  s.cmd[2] = Slew(s.cmd[2], tw.yaw_rate, kYawAccel * dt);
  const double vx = s.cmd[0], vy = s.cmd[1], wz = s.cmd[2];

  // The base: heading, tilt and velocities from the free joint.
  const mjtNum* qp = d->qpos + s.free_qpos;
  const mjtNum* qv = d->qvel + s.free_dof;  // world linear velocity, then local angular
  mjtNum r[9];
  mju_quat2Mat(r, qp + 3);
  const double yaw = std::atan2(r[3], r[0]);
  const double roll = std::atan2(r[7], r[8]);
  const double pitch = -std::asin(std::clamp(r[6], -1.0, 1.0));
  const double c = std::cos(yaw), sn = std::sin(yaw);
  const double a = std::min(1.0, dt / kVelocityFilter);
  s.vel[0] += a * ((c * qv[0] + sn * qv[1]) - s.vel[0]);
  s.vel[1] += a * ((-sn * qv[0] + c * qv[1]) - s.vel[1]);

  // The phase clock and each foot's target in the base's level frame.
  const double half = settings_.period / 2;  // stance (and swing) time
  const double phase = (d->time - s.t0) / settings_.period;
  const double max_step = kMaxStepFraction * s.height;
  std::array<bool, 4> stance{};
  int n_stance = 0;
  for (std::size_t i = 0; i < s.legs.size(); ++i) {
    const legs::Leg& leg = s.legs[i];
    State::LegState& ls = s.leg_state[i];
    double psi = phase + s.phase_offset[i];
    psi -= std::floor(psi);
    const bool swing = psi < 0.5;
    if (swing && !ls.swinging) mju_copy3(ls.lift, ls.p);
    ls.swinging = swing;
    if (swing) {
      const double sw = psi / 0.5;
      // Raibert: half a stance of commanded motion ahead of the nominal point, plus the
      // velocity error; turning moves each foot along its circle about the base.
      double land[2] = {leg.stand[0] + (vx - wz * leg.stand[1]) * half / 2 +
                            settings_.step_gain * (s.vel[0] - vx),
                        leg.stand[1] + (vy + wz * leg.stand[0]) * half / 2 +
                            settings_.step_gain * (s.vel[1] - vy)};
      const double dx = land[0] - leg.stand[0], dy = land[1] - leg.stand[1];
      const double len = std::hypot(dx, dy);
      if (len > max_step) {
        land[0] = leg.stand[0] + dx * max_step / len;
        land[1] = leg.stand[1] + dy * max_step / len;
      }
      const double e = Smooth(sw);
      ls.p[0] = ls.lift[0] + (land[0] - ls.lift[0]) * e;
      ls.p[1] = ls.lift[1] + (land[1] - ls.lift[1]) * e;
      ls.p[2] = -s.height + settings_.swing_height * 0.5 * (1 - std::cos(2 * mjPI * sw));
    } else {
      // The foot stays on the ground while the base moves at the command.
      const double px = ls.p[0], py = ls.p[1];
      ls.p[0] -= (vx - wz * py) * dt;
      ls.p[1] -= (vy + wz * px) * dt;
      ls.p[2] = -s.height;
      stance[i] = true;
      ++n_stance;
    }
  }

  // Stance forces, as the ground reactions F_i wanted on the stance feet (heading frame): the
  // weight's share with feedback on height, roll and pitch (vertical), and feedback on planar
  // velocity and yaw rate (horizontal, within what friction gives).
  double h_meas = 0, sum_x2 = 0, sum_y2 = 0, sum_r2 = 0;
  std::array<std::array<double, 3>, 4> feet{};
  std::array<double, 16> now{};  // a leg's joint angles (FindLegs allows at most 16)
  const auto angles = [&](const legs::Leg& leg) {
    const std::size_t n = leg.joints.size();
    for (std::size_t k = 0; k < n; ++k) now[k] = d->qpos[leg.joints[k].qpos_adr];
    return std::span<const double>(now.data(), n);
  };
  for (std::size_t i = 0; i < s.legs.size(); ++i) {
    double foot[3];
    legs::FootPosition(s.legs[i], angles(s.legs[i]), foot, nullptr);
    feet[i] = {foot[0], foot[1], foot[2]};
    if (stance[i]) {
      // Height of the base over this foot, in the world's vertical.
      h_meas -= r[6] * foot[0] + r[7] * foot[1] + r[8] * foot[2];
      sum_x2 += foot[0] * foot[0];
      sum_y2 += foot[1] * foot[1];
    }
  }
  sum_r2 = sum_x2 + sum_y2;
  std::fill(s.feedforward.begin(), s.feedforward.end(), 0.0);
  if (n_stance > 0) {
    h_meas /= n_stance;
    const double total =
        s.mass * (g + kHeightStiffness * (s.height - h_meas) - kHeightDamping * qv[2]);
    const double mx = -s.mass * (kAttitudeStiffness * roll + kAttitudeDamping * qv[3]);
    const double my = -s.mass * (kAttitudeStiffness * pitch + kAttitudeDamping * qv[4]);
    const double fx = s.mass * kVelocityGain * (vx - s.vel[0]) / n_stance;
    const double fy = s.mass * kVelocityGain * (vy - s.vel[1]) / n_stance;
    // Yaw: the base's inertia about the vertical through its centre of mass.
    const mjtNum* com = d->subtree_com + 3 * s.root;
    double izz = 0;
    for (int b : s.bodies) {
      const double ex = d->xipos[3 * b] - com[0], ey = d->xipos[3 * b + 1] - com[1];
      izz += m->body_inertia[3 * b + 2] + m->body_mass[b] * (ex * ex + ey * ey);
    }
    const double w_meas = r[6] * qv[3] + r[7] * qv[4] + r[8] * qv[5];
    double mz = izz * kYawGain * (wz - w_meas);
    // Turning spins the stance feet on the ground: their torsional friction (condim 4 and 6)
    // resists with up to mu_torsion * N each, which the legs must overcome.
    double torsion = 0;
    for (std::size_t i = 0; i < s.legs.size(); ++i) {
      const int fg = s.legs[i].foot_geom;
      if (stance[i] && fg >= 0 && m->geom_condim[fg] >= 4) torsion += m->geom_friction[3 * fg + 1];
    }
    mz += std::tanh(wz / 0.05) * torsion * total / n_stance;
    for (std::size_t i = 0; i < s.legs.size(); ++i) {
      if (!stance[i]) continue;
      double f[3] = {fx, fy, total / n_stance};
      if (sum_y2 > 1e-9) f[2] += mx * feet[i][1] / sum_y2;
      if (sum_x2 > 1e-9) f[2] -= my * feet[i][0] / sum_x2;
      if (sum_r2 > 1e-9) {
        f[0] -= mz * feet[i][1] / sum_r2;
        f[1] += mz * feet[i][0] / sum_r2;
      }
      f[2] = std::max(f[2], 0.0);
      const double planar = std::hypot(f[0], f[1]), limit = kFrictionUse * f[2];
      if (planar > limit) {
        f[0] *= limit / planar;
        f[1] *= limit / planar;
      }
      // The foot pushes the ground with -F: in the world, then in the base frame (R^T).
      const double world[3] = {c * f[0] - sn * f[1], sn * f[0] + c * f[1], f[2]};
      double push[3];
      for (int k = 0; k < 3; ++k) {
        push[k] = -(r[k] * world[0] + r[3 + k] * world[1] + r[6 + k] * world[2]);
      }
      const legs::Leg& leg = s.legs[i];
      const std::size_t n = leg.joints.size();
      double foot[3];
      legs::FootPosition(leg, angles(leg), foot, s.jac.data());
      for (std::size_t k = 0; k < n; ++k) {
        const double tau = s.jac[k] * push[0] + s.jac[n + k] * push[1] + s.jac[2 * n + k] * push[2];
        s.feedforward[static_cast<std::size_t>(leg.joints[k].binding)] = tau;
      }
    }
  }

  // Joint targets: the source's for actuators outside the legs, inverse kinematics for the legs;
  // a motor's damping acts on the velocity error (the targets' rate of change is known).
  const std::size_t nb = std::min(bindings_.size(), targets.size());
  std::copy_n(targets.begin(), nb, s.targets.begin());
  for (std::size_t i = 0; i < s.legs.size(); ++i) {
    State::LegState& ls = s.leg_state[i];
    const legs::Leg& leg = s.legs[i];
    for (std::size_t k = 0; k < ls.q.size(); ++k) now[k] = ls.q[k];
    legs::SolveIk(leg, ls.p, ls.q);
    for (std::size_t k = 0; k < ls.q.size(); ++k) {
      const auto b = static_cast<std::size_t>(leg.joints[k].binding);
      s.targets[b] = ls.q[k];
      if (bindings_[b].motor)
        s.feedforward[b] += gains(static_cast<int>(b)).kv * (ls.q[k] - now[k]) / dt;
    }
  }
  ApplyPositionTargets(m, d, s.targets, s.feedforward);
}

}  // namespace urlab::control
