#include "urlab/control/articulation_control.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include "urlab/control/controllers.h"

namespace urlab::control {

using physics::ArticulationBindings;
using physics::PhysicsEngine;

ArticulationControl::ArticulationControl(const ArticulationBindings& bindings)
    : prefix_(bindings.prefix()), model_(bindings.model()) {
  for (std::size_t i = 0; i < bindings.actuators().size(); ++i) {
    const physics::ActuatorView& a = bindings.actuators().all()[i];
    actuator_ids_.push_back(a.id);  // ElementSet is in id order
    actuator_names_.push_back(bindings.actuators().short_names()[i]);
    if (a.act_adr >= 0) act_adrs_.push_back(a.act_adr);
  }
  for (const physics::JointView& j : bindings.joints().all()) {
    for (int k = 0; k < j.qpos_size; ++k) qpos_adrs_.push_back(j.qpos_adr + k);
    for (int k = 0; k < j.dof_size; ++k) dof_adrs_.push_back(j.dof_adr + k);
  }
  for (const physics::BodyView& b : bindings.bodies().all()) {
    body_ids_.push_back(b.id);
    if (b.mocap_id >= 0) mocap_ids_.push_back(b.mocap_id);
  }
  for (auto& c : channels_) c = std::make_unique<FrameChannel>(actuator_ids_.size());
  SetController(std::make_unique<PassthroughController>());
}

int ArticulationControl::IndexOf(std::string_view short_name) const {
  for (std::size_t i = 0; i < actuator_names_.size(); ++i) {
    if (actuator_names_[i] == short_name) return static_cast<int>(i);
  }
  return -1;
}

void ArticulationControl::SetController(std::unique_ptr<Controller> controller) {
  if (!controller) throw Error("ArticulationControl::SetController: null controller");
  controller->Bind(model_, actuator_ids_);
  controller_ = std::move(controller);
}

FrameChannel& ArticulationControl::channel(ControlSource source) const {
  const int i = static_cast<int>(source);
  if (i < 0 || i >= kNumControlSources) throw Error("ArticulationControl: bad control source");
  return *channels_[static_cast<std::size_t>(i)];
}

bool ArticulationControl::PublishFrame(ControlSource source, std::span<const double> targets,
                                       std::span<const double> kp, std::span<const double> kv) {
  return channel(source).Publish(targets, kp, kv);
}

bool ArticulationControl::SetTarget(ControlSource source, int index, double value) {
  return channel(source).Set(index, value);
}

bool ArticulationControl::SetTarget(ControlSource source, std::string_view short_name,
                                    double value) {
  return SetTarget(source, IndexOf(short_name), value);
}

double ArticulationControl::GetTarget(ControlSource source, int index) const {
  return channel(source).Get(index);
}

void ArticulationControl::SetSourceOverride(std::optional<ControlSource> source) {
  override_.store(source ? static_cast<int>(*source) : -1, std::memory_order_relaxed);
}

std::optional<ControlSource> ArticulationControl::source_override() const {
  const int v = override_.load(std::memory_order_relaxed);
  if (v < 0) return std::nullopt;
  return static_cast<ControlSource>(v);
}

ControlSource ArticulationControl::EffectiveSource(ControlSource global) const {
  if (holding()) return ControlSource::kHold;
  return source_override().value_or(global);
}

int ArticulationControl::FindKeyframe(const mjModel* m, std::string_view name) const {
  const std::string exact(name);
  int key = mj_name2id(m, mjOBJ_KEY, exact.c_str());
  if (key < 0) key = mj_name2id(m, mjOBJ_KEY, (prefix_ + exact).c_str());
  return key;
}

void ArticulationControl::HoldKeyframe(std::string_view name) {
  const int key = FindKeyframe(model_, name);
  if (key < 0) throw Error("HoldKeyframe: no keyframe '" + std::string(name) + "'");
  HoldKeyframe(key);
}

std::vector<double> ArticulationControl::PoseTargets(int key) const {
  const mjModel* m = model_;
  const bool positions = controller_->TargetsArePositions();
  std::vector<double> pose(actuator_ids_.size(), 0.0);
  for (std::size_t i = 0; i < actuator_ids_.size(); ++i) {
    const ActuatorBinding b = MakeActuatorBinding(m, actuator_ids_[i]);
    if (key >= 0) pose[i] = m->key_ctrl[key * m->nu + b.actuator_id];
    if (positions && b.has_joint()) {
      pose[i] = key >= 0 ? m->key_qpos[key * m->nq + b.qpos_adr] : m->qpos0[b.qpos_adr];
    }
  }
  return pose;
}

void ArticulationControl::HoldKeyframe(int key) {
  if (key < 0 || key >= model_->nkey) {
    throw Error("HoldKeyframe: keyframe id " + std::to_string(key) + " out of range");
  }
  channel(ControlSource::kHold).Publish(PoseTargets(key));  // the whole pose, then the switch
  holding_.store(true, std::memory_order_release);
}

void ArticulationControl::SeedTargets(int key) {
  if (key >= model_->nkey) throw Error("SeedTargets: keyframe id out of range");
  const std::vector<double> pose = PoseTargets(key);
  for (const ControlSource s :
       {ControlSource::kNetwork, ControlSource::kUi, ControlSource::kInput}) {
    channel(s).Publish(pose);
  }
}

void ArticulationControl::SetControlDelay(const physics::DelaySpec& spec, ControlSource global) {
  control_delay_.Configure(spec);
  RestartControlDelay(global);
}

void ArticulationControl::RestartControlDelay(ControlSource global) {
  control_delay_.Restart();
  if (control_delay_.active()) control_delay_.Prime(channel(EffectiveSource(global)).Read());
}

const CommandFrame& ArticulationControl::ApplyControls(const mjModel* m, mjData* d,
                                                       ControlSource global) {
  const CommandFrame& arrived = channel(EffectiveSource(global)).Read();
  const CommandFrame& frame = control_delay_.active() ? control_delay_.Push(arrived) : arrived;
  if (frame.raw) {  // the targets are the controls: no controller, no twist
    for (std::size_t i = 0; i < actuator_ids_.size() && i < frame.targets.size(); ++i) {
      d->ctrl[actuator_ids_[i]] = frame.targets[i];
    }
    return frame;
  }
  controller_->UseFrameGains(frame.kp, frame.kv);
  controller_->ComputeAndApply(m, d, frame.targets);
  if (twist_) twist_->Apply(m, d);
  return frame;
}

void ArticulationControl::ResetToKeyframe(const mjModel* m, mjData* d, int key) const {
  if (key < 0 || key >= m->nkey) return;
  for (int a : qpos_adrs_) d->qpos[a] = m->key_qpos[key * m->nq + a];
  for (int a : dof_adrs_) {
    d->qvel[a] = m->key_qvel[key * m->nv + a];
    d->qacc_warmstart[a] = 0;
    d->qfrc_applied[a] = 0;
  }
  for (int a : act_adrs_) d->act[a] = m->key_act[key * m->na + a];
  for (int u : actuator_ids_) d->ctrl[u] = m->key_ctrl[key * m->nu + u];
  for (int k : mocap_ids_) {
    std::memcpy(d->mocap_pos + 3 * k, m->key_mpos + key * 3 * m->nmocap + 3 * k,
                3 * sizeof(mjtNum));
    std::memcpy(d->mocap_quat + 4 * k, m->key_mquat + key * 4 * m->nmocap + 4 * k,
                4 * sizeof(mjtNum));
  }
  for (int b : body_ids_) std::memset(d->xfrc_applied + 6 * b, 0, 6 * sizeof(mjtNum));
}

// ---------------------------------------------------------------------------------------------
// ControlSystem

ArticulationControl& ControlSystem::Add(std::unique_ptr<ArticulationControl> articulation) {
  if (!articulation) throw Error("ControlSystem::Add: null articulation");
  if (Find(articulation->prefix())) {
    throw Error("ControlSystem::Add: articulation '" + articulation->prefix() + "' already added");
  }
  all_.push_back(std::move(articulation));
  return *all_.back();
}

ArticulationControl* ControlSystem::Find(std::string_view prefix) const {
  for (const auto& a : all_) {
    if (a->prefix() == prefix) return a.get();
  }
  return nullptr;
}

void ControlSystem::Install(PhysicsEngine& engine) {
  std::vector<physics::CommandGroupLayout> layout;
  for (const auto& a : all_) {
    // Named as the scene names the articulation: its prefix without the joining '_'.
    std::string name = a->prefix();
    if (name.size() > 1 && name.back() == '_') name.pop_back();
    layout.push_back({std::move(name), a->actuator_ids()});
  }
  engine.SetCommandLayout(std::move(layout));
  PhysicsEngine* e = &engine;
  engine.SetApplyControlsHook(
      [this, e](const mjModel* m, mjData* d) { ApplyControls(m, d, &e->applied_commands()); });
  // A reset or restore starts every control delay afresh (the same seed, the same delays).
  engine.AddCommandListener(
      [this](const physics::AppliedCommand& c, const mjModel*, const mjData*) {
        if (c.discontinuity & (physics::kDiscontinuityReset | physics::kDiscontinuityRestore)) {
          for (const auto& a : all_) a->RestartControlDelay(global_source());
        }
      });
}

void ControlSystem::ApplyControls(const mjModel* m, mjData* d, physics::AppliedCommands* applied) {
  const ControlSource global = global_source();
  std::size_t offset = 0;
  for (std::size_t i = 0; i < all_.size(); ++i) {
    const CommandFrame& frame = all_[i]->ApplyControls(m, d, global);
    if (!applied || i >= applied->seq.size()) continue;
    const std::size_t n = frame.targets.size();
    if (offset + n > applied->targets.size()) continue;
    std::copy(frame.targets.begin(), frame.targets.end(), applied->targets.begin() + offset);
    const auto gains = [&](const std::vector<double>& g, std::vector<double>* out) {
      if (g.size() == n) {
        std::copy(g.begin(), g.end(), out->begin() + offset);
      } else {
        std::fill_n(out->begin() + offset, n, std::numeric_limits<double>::quiet_NaN());
      }
    };
    gains(frame.kp, &applied->kp);
    gains(frame.kv, &applied->kv);
    applied->seq[i] = frame.seq;
    applied->source[i] = static_cast<std::uint8_t>(all_[i]->EffectiveSource(global));
    applied->raw[i] = frame.raw ? 1 : 0;
    offset += n;
  }
}

std::uint64_t ControlSystem::RequestKeyframeReset(PhysicsEngine& engine, std::string_view prefix,
                                                  std::string_view key_name) const {
  const ArticulationControl* a = Find(prefix);
  if (!a) throw Error("RequestKeyframeReset: no articulation '" + std::string(prefix) + "'");
  const int key = a->FindKeyframe(engine.model(), key_name);
  if (key < 0) {
    throw Error("RequestKeyframeReset: no keyframe '" + std::string(key_name) + "' or '" +
                std::string(prefix) + std::string(key_name) + "'");
  }
  return engine.ResetWith([a, key](const mjModel* m, mjData* d) { a->ResetToKeyframe(m, d, key); },
                          "reset articulation '" + std::string(prefix) + "' to keyframe '" +
                              std::string(key_name) + "'");
}

}  // namespace urlab::control
