#include "urlab/control/controller.h"

#include <algorithm>

namespace urlab::control {

namespace {
constexpr const char* kSourceNames[kNumControlSources] = {"network", "ui", "input", "hold",
                                                          "replay"};
}  // namespace

const char* ToString(ControlSource source) {
  const int i = static_cast<int>(source);
  return i >= 0 && i < kNumControlSources ? kSourceNames[i] : "?";
}

std::optional<ControlSource> ParseControlSource(std::string_view name) {
  for (int i = 0; i < kNumControlSources; ++i) {
    if (name == kSourceNames[i]) return static_cast<ControlSource>(i);
  }
  return std::nullopt;
}

double ActuatorBinding::ClampToJoint(double q) const {
  return joint_limited ? std::clamp(q, joint_range[0], joint_range[1]) : q;
}

double ActuatorBinding::ClampCtrl(double u) const {
  return ctrl_limited ? std::clamp(u, ctrl_range[0], ctrl_range[1]) : u;
}

bool ActuatorBinding::TargetRange(bool position_targets, double range[2]) const {
  if (position_targets && has_joint()) {
    if (!joint_limited) return false;
    range[0] = joint_range[0];
    range[1] = joint_range[1];
    if (!motor && ctrl_limited) {
      range[0] = std::clamp(range[0], ctrl_range[0], ctrl_range[1]);
      range[1] = std::clamp(range[1], ctrl_range[0], ctrl_range[1]);
    }
    return true;
  }
  if (!ctrl_limited) return false;
  range[0] = ctrl_range[0];
  range[1] = ctrl_range[1];
  return true;
}

ActuatorBinding MakeActuatorBinding(const mjModel* m, int id) {
  ActuatorBinding b;
  b.actuator_id = id;
  const int trn = m->actuator_trntype[id];
  const int j = m->actuator_trnid[2 * id];
  if ((trn == mjTRN_JOINT || trn == mjTRN_JOINTINPARENT) && j >= 0 &&
      (m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE)) {
    b.joint_id = j;
    b.qpos_adr = m->jnt_qposadr[j];
    b.dof_adr = m->jnt_dofadr[j];
    b.joint_limited = m->jnt_limited[j] != 0;
    b.joint_range[0] = m->jnt_range[2 * j];
    b.joint_range[1] = m->jnt_range[2 * j + 1];
  }
  b.motor = m->actuator_gaintype[id] == mjGAIN_FIXED && m->actuator_biastype[id] == mjBIAS_NONE &&
            m->actuator_dyntype[id] == mjDYN_NONE;
  b.gain = m->actuator_gainprm[mjNGAIN * id];
  b.gear = m->actuator_gear[6 * id];
  b.ctrl_limited = m->actuator_ctrllimited[id] != 0;
  b.ctrl_range[0] = m->actuator_ctrlrange[2 * id];
  b.ctrl_range[1] = m->actuator_ctrlrange[2 * id + 1];
  return b;
}

void Controller::Bind(const mjModel* m, std::span<const int> actuator_ids) {
  std::vector<int> ids(actuator_ids.begin(), actuator_ids.end());
  std::sort(ids.begin(), ids.end());
  bindings_.clear();
  for (int id : ids) {
    if (id >= 0 && id < m->nu) bindings_.push_back(MakeActuatorBinding(m, id));
  }
}

int Controller::IndexOfActuator(int id) const {
  auto it = std::lower_bound(bindings_.begin(), bindings_.end(), id,
                             [](const ActuatorBinding& b, int v) { return b.actuator_id < v; });
  return it != bindings_.end() && it->actuator_id == id ? static_cast<int>(it - bindings_.begin())
                                                        : -1;
}

}  // namespace urlab::control
