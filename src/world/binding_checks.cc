#include "world/binding_checks.h"

#include <algorithm>
#include <string>
#include <vector>

#include "urlab/physics/free_base.h"

namespace urlab::world {

namespace {

// The short names of the elements of type `type` whose names carry `prefix`, in id order.
std::vector<std::string> ShortNames(const mjModel* m, mjtObj type, int count,
                                    const std::string& prefix) {
  std::vector<std::string> out;
  for (int i = 0; i < count; ++i) {
    const char* name = mj_id2name(m, type, i);
    if (name && std::string_view(name).starts_with(prefix)) {
      out.emplace_back(std::string_view(name).substr(prefix.size()));
    }
  }
  return out;
}

std::string List(const std::vector<std::string>& names) {
  if (names.empty()) return "none";
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

bool Contains(const std::vector<std::string>& v, const std::string& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

void CheckCameras(const ArticulationConfig& config, const mjModel* m, const std::string& prefix,
                  Diagnostics& sink) {
  const std::vector<std::string> cams = ShortNames(m, mjOBJ_CAMERA, m->ncam, prefix);
  auto require = [&](const std::string& cam, const SourceLocation& where, const std::string& what) {
    if (Contains(cams, cam)) return;
    sink.Error(where, what + ": articulation '" + config.name + "' has no camera '" + cam +
                          "' in its MJCF " + config.mjcf + " (it has: " + List(cams) + ")");
  };
  for (const std::string& cam : config.cameras)
    require(cam, config.where, config.name + ".cameras");
}

void CheckTwist(const ArticulationConfig& config, const mjcf::ArticulationLayout& layout,
                const mjModel* m, Diagnostics& sink) {
  if (!config.twist_given || physics::FreeBaseJoint(m, layout.prefix) >= 0) return;
  sink.Error(config.where, config.name +
                               ": twist needs a free base (a freejoint on the root body); " +
                               config.mjcf + " has none, so nothing could drive it");
}

void CheckInput(const SceneConfig& scene, const ArticulationConfig& config, const mjModel* m,
                const std::string& prefix, Diagnostics& sink) {
  if (config.input.empty()) return;
  const std::vector<std::string> actuators = ShortNames(m, mjOBJ_ACTUATOR, m->nu, prefix);
  const std::vector<std::string> joints = ShortNames(m, mjOBJ_JOINT, m->njnt, prefix);
  for (const InputBindingConfig& b : config.input) {
    if (Contains(actuators, b.actuator)) continue;
    std::string why;
    if (Contains(joints, b.actuator)) {
      why = "; '" + b.actuator + "' is a joint: name the actuator that drives it";
    } else {
      // Another articulation's actuator, by its short or its full (prefixed) name.
      for (const ArticulationConfig& other : scene.articulations) {
        if (&other == &config) continue;
        const std::string other_prefix = other.name + "_";
        const bool full = b.actuator.starts_with(other_prefix) &&
                          mj_name2id(m, mjOBJ_ACTUATOR, b.actuator.c_str()) >= 0;
        const bool short_name =
            mj_name2id(m, mjOBJ_ACTUATOR, (other_prefix + b.actuator).c_str()) >= 0;
        if (full || short_name) {
          why = "; it is an actuator of articulation '" + other.name +
                "' (a binding drives its own articulation's actuators)";
          break;
        }
      }
    }
    sink.Error(b.where, config.name + ".input: no actuator '" + b.actuator + "' in " + config.mjcf +
                            why + " (its actuators: " + List(actuators) + ")");
  }
}

}  // namespace

void CheckArticulationBindings(const SceneConfig& scene, const ArticulationConfig& config,
                               const mjcf::ArticulationLayout& layout, const mjModel* m,
                               Diagnostics& sink) {
  CheckCameras(config, m, layout.prefix, sink);
  CheckTwist(config, layout, m, sink);
  CheckInput(scene, config, m, layout.prefix, sink);
}

}  // namespace urlab::world
