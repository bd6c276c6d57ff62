#include "urlab/control/controllers.h"

#include <algorithm>
#include <cmath>

#include "urlab/core/error.h"

namespace urlab::control {

// ---------------------------------------------------------------------------------------------
// PassthroughController

void PassthroughController::ComputeAndApply(const mjModel*, mjData* d,
                                            std::span<const double> targets) {
  const std::size_t n = std::min(bindings_.size(), targets.size());
  for (std::size_t i = 0; i < n; ++i) {
    d->ctrl[bindings_[i].actuator_id] = bindings_[i].ClampCtrl(targets[i]);
  }
}

// ---------------------------------------------------------------------------------------------
// PdController

PdController::PdController(PdGains defaults) : defaults_(defaults) {}

void PdController::Bind(const mjModel* m, std::span<const int> actuator_ids) {
  Controller::Bind(m, actuator_ids);
  gains_.reset(new AtomicGains[bindings_.size()]);
  for (std::size_t i = 0; i < bindings_.size(); ++i) SetGains(static_cast<int>(i), defaults_);
}

void PdController::SetGains(int i, PdGains g) {
  if (i < 0 || i >= static_cast<int>(bindings_.size())) {
    throw Error("PdController::SetGains: index " + std::to_string(i) + " out of range");
  }
  AtomicGains& a = gains_[static_cast<std::size_t>(i)];
  a.kp.store(g.kp, std::memory_order_relaxed);
  a.kv.store(g.kv, std::memory_order_relaxed);
  a.limit.store(g.torque_limit, std::memory_order_relaxed);
}

PdGains PdController::gains(int i) const {
  if (i < 0 || i >= static_cast<int>(bindings_.size())) {
    throw Error("PdController::gains: index " + std::to_string(i) + " out of range");
  }
  const AtomicGains& a = gains_[static_cast<std::size_t>(i)];
  return {a.kp.load(std::memory_order_relaxed), a.kv.load(std::memory_order_relaxed),
          a.limit.load(std::memory_order_relaxed)};
}

void PdController::ComputeAndApply(const mjModel* m, mjData* d, std::span<const double> targets) {
  ApplyPositionTargets(m, d, targets);
}

void PdController::ApplyPositionTargets(const mjModel*, mjData* d, std::span<const double> targets,
                                        std::span<const double> feedforward) {
  const std::size_t n = std::min(bindings_.size(), targets.size());
  for (std::size_t i = 0; i < n; ++i) {
    const ActuatorBinding& b = bindings_[i];
    const double target = b.has_joint() ? b.ClampToJoint(targets[i]) : targets[i];
    const double ff = i < feedforward.size() ? feedforward[i] : 0.0;
    double u = target;
    if (ff != 0 && !b.motor && b.gain * b.gear != 0) u = target + ff / (b.gain * b.gear);
    if (b.motor && b.has_joint()) {
      const AtomicGains& g = gains_[i];
      const double limit = g.limit.load(std::memory_order_relaxed);
      const double kp = i < frame_kp_.size() && !std::isnan(frame_kp_[i])
                            ? frame_kp_[i]
                            : g.kp.load(std::memory_order_relaxed);
      const double kv = i < frame_kv_.size() && !std::isnan(frame_kv_[i])
                            ? frame_kv_[i]
                            : g.kv.load(std::memory_order_relaxed);
      double tau = kp * (target - d->qpos[b.qpos_adr]) - kv * d->qvel[b.dof_adr] + ff;
      tau = std::clamp(tau, -limit, limit);
      const double scale = b.gain * b.gear;
      u = scale != 0 ? tau / scale : 0;
    }
    d->ctrl[b.actuator_id] = b.ClampCtrl(u);
  }
}

// ---------------------------------------------------------------------------------------------
// KeyframeController

KeyframeController::KeyframeController(Options options, PdGains gains)
    : PdController(gains), options_(options) {}

double KeyframeController::Ease(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

void KeyframeController::Bind(const mjModel* m, std::span<const int> actuator_ids) {
  PdController::Bind(m, actuator_ids);
  start_pose_.assign(bindings_.size(), 0);
  targets_.assign(bindings_.size(), 0);
}

void KeyframeController::AddPose(KeyframePose pose) {
  if (pose.positions.size() != bindings_.size()) {
    throw Error("KeyframeController: pose '" + pose.name + "' has " +
                std::to_string(pose.positions.size()) + " positions for " +
                std::to_string(bindings_.size()) + " actuators (Bind first)");
  }
  if (pose.blend_time < 0 || pose.hold_time < 0) {
    throw Error("KeyframeController: pose '" + pose.name + "' has a negative time");
  }
  poses_.push_back(std::move(pose));
}

KeyframePose KeyframeController::PoseFromModelKey(const mjModel* m, int key, double blend_time,
                                                  double hold_time) const {
  if (key < 0 || key >= m->nkey) throw Error("PoseFromModelKey: keyframe id out of range");
  KeyframePose p;
  const char* name = mj_id2name(m, mjOBJ_KEY, key);
  p.name = name ? name : "key" + std::to_string(key);
  p.blend_time = blend_time;
  p.hold_time = hold_time;
  for (const ActuatorBinding& b : bindings_) {
    p.positions.push_back(b.has_joint() ? m->key_qpos[key * m->nq + b.qpos_adr] : 0.0);
  }
  return p;
}

void KeyframeController::Start(const mjData* d) {
  t0_ = d->time;
  for (std::size_t i = 0; i < bindings_.size(); ++i) {
    start_pose_[i] = bindings_[i].has_joint() ? d->qpos[bindings_[i].qpos_adr] : 0.0;
  }
  playing_.store(true, std::memory_order_release);
}

void KeyframeController::Evaluate(double t) {
  double elapsed = t - t0_ - options_.start_delay;
  auto set = [&](const std::vector<double>& pose, int index, bool blending) {
    std::copy(pose.begin(), pose.end(), targets_.begin());
    current_pose_.store(index, std::memory_order_release);
    blending_.store(blending, std::memory_order_release);
  };
  if (elapsed < 0 || poses_.empty()) return set(start_pose_, -1, false);
  double cycle = 0;
  for (const KeyframePose& p : poses_) cycle += p.blend_time + p.hold_time;
  const std::vector<double>* before_first = &start_pose_;
  if (elapsed >= cycle) {
    if (!options_.loop || cycle <= 0) {
      return set(poses_.back().positions, static_cast<int>(poses_.size()) - 1, false);
    }
    elapsed = std::fmod(elapsed - cycle, cycle);
    before_first = &poses_.back().positions;
  }
  for (std::size_t i = 0; i < poses_.size(); ++i) {
    const KeyframePose& p = poses_[i];
    if (elapsed < p.blend_time) {
      const std::vector<double>& from = i == 0 ? *before_first : poses_[i - 1].positions;
      const double s = Ease(elapsed / p.blend_time);
      for (std::size_t k = 0; k < targets_.size(); ++k) {
        targets_[k] = from[k] + s * (p.positions[k] - from[k]);
      }
      current_pose_.store(static_cast<int>(i), std::memory_order_release);
      blending_.store(true, std::memory_order_release);
      return;
    }
    elapsed -= p.blend_time;
    if (elapsed < p.hold_time) return set(p.positions, static_cast<int>(i), false);
    elapsed -= p.hold_time;
  }
  set(poses_.back().positions, static_cast<int>(poses_.size()) - 1, false);
}

void KeyframeController::Restart() {
  if (playing()) play_requested_.store(true, std::memory_order_release);
}

void KeyframeController::ComputeAndApply(const mjModel* m, mjData* d,
                                         std::span<const double> targets) {
  if (stop_requested_.exchange(false, std::memory_order_acq_rel)) {
    playing_.store(false, std::memory_order_release);
    current_pose_.store(-1, std::memory_order_release);
    blending_.store(false, std::memory_order_release);
  }
  if (play_requested_.exchange(false, std::memory_order_acq_rel)) Start(d);
  if (options_.autoplay) {
    options_.autoplay = false;  // once, at the first step
    if (!playing()) Start(d);
  }
  if (!playing()) return ApplyPositionTargets(m, d, targets);
  if (d->time < t0_) Start(d);  // time went backwards: a reset restarts the sequence
  Evaluate(d->time);
  ApplyPositionTargets(m, d, targets_);
}

}  // namespace urlab::control
