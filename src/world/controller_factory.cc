#include "urlab/world/controller_factory.h"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "urlab/control/gait.h"
#include "urlab/physics/free_base.h"
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

// The actuators a controller binds: the articulation's, by prefix (ArticulationControl).
std::vector<int> ArticulationActuators(const mjModel* m, const std::string& prefix) {
  std::vector<int> ids;
  for (int id = 0; id < m->nu; ++id) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, id);
    if (name && std::string_view(name).starts_with(prefix)) ids.push_back(id);
  }
  return ids;
}

// The gait's settings with its standing keyframe: the articulation's initial keyframe, else its
// first keyframe, else qpos0.
control::GaitSettings GaitSettingsFor(const ArticulationConfig& config, const mjModel* m,
                                      const std::string& prefix) {
  control::GaitSettings g = config.controller.gait;
  g.stand_key = -1;
  if (!config.keyframe.empty()) {
    g.stand_key = mj_name2id(m, mjOBJ_KEY, (prefix + config.keyframe).c_str());
  }
  for (int k = 0; k < m->nkey && g.stand_key < 0; ++k) {
    const char* name = mj_id2name(m, mjOBJ_KEY, k);
    if (name && std::string_view(name).starts_with(prefix)) g.stand_key = k;
  }
  return g;
}

}  // namespace

void CheckController(const ArticulationConfig& config, const mjModel* m, const std::string& prefix,
                     Diagnostics& sink) {
  const ControllerConfig& c = config.controller;
  if (c.type == "pd" || c.type == "keyframe" || c.type == "gait") {
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
                            ": controller gains apply to pd, keyframe and gait controllers, "
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
  if (c.type == "gait") {
    // The legs are found as InstallController finds them.
    try {
      control::GaitController gait(GaitSettingsFor(config, m, prefix), control::PdGains{});
      gait.Bind(m, ArticulationActuators(m, prefix));
    } catch (const Error& e) {
      sink.Error(c.where, config.name + ": " + e.what() + " in " + config.mjcf);
    }
  }
  if (config.twist_mode_given) {
    const control::TwistMode mode = config.twist.mode;
    if (c.type == "gait" && mode != control::TwistMode::kGait) {
      sink.Error(config.where, config.name + ": twist mode " + control::ToString(mode) +
                                   " with a gait controller (the gait walks at the twist; hover "
                                   "pushes the base and is for bodies without legs)");
    } else if (c.type != "gait" && mode == control::TwistMode::kGait) {
      sink.Error(
          config.where,
          config.name + ": twist mode gait needs `controller: {type: gait}`, not '" + c.type + "'");
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
  } else if (c.type == "gait") {
    auto gait = std::make_unique<control::GaitController>(
        GaitSettingsFor(config, m, control.prefix()), defaults);
    control::GaitController* g = gait.get();
    control.SetController(std::move(gait));  // finds the legs (checked above)
    ApplyJointGains(config, control, m, *g);
  } else {
    throw InputError(c.where, config.name + ": unknown controller type '" + c.type + "'");
  }
}

void InstallTwist(const ArticulationConfig& config, const physics::ArticulationBindings& bindings,
                  control::ArticulationControl& control, const mjModel* m) {
  if (const int base = physics::FreeBaseIndex(bindings); base >= 0) {
    const physics::JointView& j = bindings.joints().all()[static_cast<std::size_t>(base)];
    auto* gait = dynamic_cast<control::GaitController*>(control.controller());
    control::TwistSettings settings = config.twist;
    if (!config.twist_mode_given) {
      settings.mode = gait ? control::TwistMode::kGait : control::TwistMode::kPolicy;
    }
    auto twist = std::make_unique<control::TwistController>(settings);
    twist->Bind(m, j.id);
    if (gait) gait->SetTwistSource(twist.get());
    control.SetTwistController(std::move(twist));
    return;
  }
  if (config.twist_given) {
    throw InputError(config.where,
                     config.name + ": twist needs a free base (a freejoint on the root body)");
  }
}

}  // namespace urlab::world
