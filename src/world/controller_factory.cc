#include "urlab/world/controller_factory.h"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "urlab/world/names.h"

namespace urlab::world {

namespace {

// Short (unprefixed) name of an element, "" when unnamed or outside the prefix.
std::string ShortName(const mjModel* m, mjtObj type, int id, const std::string& prefix) {
  const char* name = id >= 0 ? mj_id2name(m, type, id) : nullptr;
  if (!name) return "";
  const std::string_view full(name);
  return full.starts_with(prefix) ? std::string(full.substr(prefix.size())) : "";
}

// True when a gains key names binding `b`'s actuator or the joint it drives (short or full name,
// world/names.h).
bool GainKeyMatches(const mjModel* m, const control::ActuatorBinding& b, const std::string& prefix,
                    const std::string& key) {
  const auto named = [&](mjtObj type, int id) {
    if (id < 0 || ShortName(m, type, id, prefix).empty()) return false;
    const std::vector<int> ids = NameCandidates(m, type, prefix, key);
    return std::find(ids.begin(), ids.end(), id) != ids.end();
  };
  return named(mjOBJ_ACTUATOR, b.actuator_id) || named(mjOBJ_JOINT, b.joint_id);
}

// Applies the per-joint/actuator gains of `config` over the controller's defaults (the keys were
// checked by CheckController).
void ApplyJointGains(const ArticulationConfig& config, const control::ArticulationControl& control,
                     const mjModel* m, control::PdController& pd) {
  for (const auto& [key, gains] : config.controller.gains) {
    for (std::size_t i = 0; i < pd.bindings().size(); ++i) {
      if (GainKeyMatches(m, pd.bindings()[i], control.prefix(), key)) {
        pd.SetGains(static_cast<int>(i), MergeGains(pd.default_gains(), gains));
      }
    }
  }
}

}  // namespace

void CheckController(const ArticulationConfig& config, const mjModel* m, const std::string& prefix,
                     Diagnostics& sink) {
  const ControllerConfig& c = config.controller;
  if (c.type == "pd" || c.type == "keyframe") {
    // The actuators a controller binds: the articulation's, by prefix (ArticulationControl).
    std::vector<control::ActuatorBinding> bindings;
    for (int id = 0; id < m->nu; ++id) {
      const char* name = mj_id2name(m, mjOBJ_ACTUATOR, id);
      if (name && std::string_view(name).starts_with(prefix)) {
        bindings.push_back(control::MakeActuatorBinding(m, id));
      }
    }
    for (const auto& [key, gains] : c.gains) {
      bool found = false;
      for (const control::ActuatorBinding& b : bindings) found |= GainKeyMatches(m, b, prefix, key);
      if (!found) {
        sink.Error(c.where, config.name + ": controller gains: no actuated joint or actuator '" +
                                key + "' in " + config.mjcf);
      }
    }
  } else if (!c.gains.empty()) {
    sink.Error(c.where, config.name +
                            ": controller gains apply to pd and keyframe controllers, "
                            "not '" +
                            c.type + "'");
  }
  if (c.type == "keyframe") {
    for (const KeyframeStep& step : c.sequence) {
      // Only this articulation's keyframes, by short or full name (world/names.h).
      try {
        if (FindNamed(m, mjOBJ_KEY, prefix, step.keyframe) < 0) {
          sink.Error(c.where, config.name + ": controller sequence: keyframe '" + step.keyframe +
                                  "' is not in " + config.mjcf);
        }
      } catch (const Error& e) {
        sink.Error(c.where, config.name + ": controller sequence: " + e.what());
      }
    }
  }
}

control::PdGains MergeGains(const control::PdGains& base, const PdGains& config) {
  control::PdGains g = base;
  if (config.kp) g.kp = *config.kp;
  if (config.kv) g.kv = *config.kv;
  if (config.torque_limit) g.torque_limit = *config.torque_limit;
  return g;
}

void InstallController(const ArticulationConfig& config, control::ArticulationControl& control,
                       const mjModel* m) {
  Diagnostics problems;
  CheckController(config, m, control.prefix(), problems);
  problems.ThrowIfErrors();
  const ControllerConfig& c = config.controller;
  const control::PdGains defaults = MergeGains(control::PdGains{}, c.defaults);
  if (c.type == "none" || c.type == "passthrough") {
    control.Use(std::make_unique<control::PassthroughController>());
  } else if (c.type == "pd") {
    auto& pd = control.Use(std::make_unique<control::PdController>(defaults));
    ApplyJointGains(config, control, m, pd);
  } else if (c.type == "keyframe") {
    control::KeyframeController::Options options;
    options.loop = c.loop;
    options.autoplay = c.autoplay;
    options.start_delay = c.start_delay;
    auto& kf = control.Use(std::make_unique<control::KeyframeController>(options, defaults));
    ApplyJointGains(config, control, m, kf);
    for (const KeyframeStep& step : c.sequence) {
      // Only this articulation's keyframes (checked above).
      const int key = FindNamed(m, mjOBJ_KEY, control.prefix(), step.keyframe);
      kf.AddPose(kf.PoseFromModelKey(m, key, step.blend, step.hold));
    }
  } else {
    throw InputError(c.where, config.name + ": unknown controller type '" + c.type + "'");
  }
}

void InstallTwist(const ArticulationConfig& config, const physics::ArticulationBindings& bindings,
                  control::ArticulationControl& control, const mjModel* m) {
  for (const physics::JointView& j : bindings.joints().all()) {
    if (j.type != mjJNT_FREE) continue;
    auto twist = std::make_unique<control::TwistController>(config.twist);
    twist->Bind(m, j.id);
    control.SetTwistController(std::move(twist));
    return;
  }
  if (config.twist_given) {
    throw InputError(config.where,
                     config.name + ": twist needs a free base (a freejoint on the root body)");
  }
}

}  // namespace urlab::world
