// The scene's `randomize:` section (urlab/world/randomize_settings.h): gravity components, and per
// articulation or prop its parameters (the table of world/randomize.h), each a distribution.
// Names are checked against the scene's articulations and props, at their file:line.
#include <any>
#include <string>
#include <vector>

#include "urlab/world/randomize_settings.h"
#include "world/scene_section.h"

namespace urlab::world {

namespace {

// A range: {uniform: [low, high]}, {normal: [mean, std]} or {log_uniform: [low, high]}.
RandomRange Range(const SectionReader& r, const YAML::Node& n, const std::string& where,
                  std::string_view key) {
  const auto entries = r.Entries(n, where);
  if (entries.size() != 1) {
    r.Fail(n, where +
                  " must be one of {uniform: [low, high]}, {normal: [mean, std]}, "
                  "{log_uniform: [low, high]}");
  }
  const auto& [dist, v] = entries.front();
  const std::vector<double> ab = r.Numbers(v, where + "." + dist, 2);
  RandomRange out;
  const std::string problem = MakeRange(dist, ab[0], ab[1], &out);
  if (!problem.empty()) r.Fail(v, where + ": " + problem);
  if (const std::string outside = CheckLimits(key, out); !outside.empty()) {
    r.Fail(v, where + ": " + outside);
  }
  return out;
}

std::any Parse(const SectionReader& r, const YAML::Node& n, const SceneConfig& s) {
  RandomizeSettings settings;
  settings.where = r.At(n);
  RandomizeConfig& c = settings.config;
  for (const auto& [name, v] : r.Entries(n, "randomize")) {
    const std::string where = "randomize." + name;
    if (name == "gravity") {
      r.CheckKeys(v, where, {"x", "y", "z"});
      for (const auto& [axis, range] : r.Entries(v, where)) {
        c.gravity[axis] = Range(r, range, where + "." + axis, "gravity");
      }
      continue;
    }
    const ArticulationConfig* art = nullptr;
    for (const auto& a : s.articulations) {
      if (a.name == name) art = &a;
    }
    bool prop = false;
    for (const auto& p : s.props) prop |= p.spec.name == name;
    if (!art && !prop) {
      r.Fail(v, where + ": no articulation or prop '" + name + "' in the scene (or 'gravity')");
    }
    auto& params = c.targets[name];
    for (const auto& [key, range] : r.Entries(v, where)) {
      if (!IsRandomParam(key, prop)) {
        std::string known;
        for (const RandomParamInfo& p : RandomParams()) {
          if (!prop || p.props) known += (known.empty() ? "" : ", ") + std::string(p.key);
        }
        r.Fail(range, where + ": unknown parameter '" + key + "' (expected one of: " + known + ")");
      }
      if ((key == "kp" || key == "kv") && art && art->controller.type != "pd" &&
          art->controller.type != "gait") {
        r.Fail(range, where + "." + key + " needs a PD controller (controller type pd or gait)");
      }
      params[key] = Range(r, range, where + "." + key, key);
    }
  }
  return settings;
}

}  // namespace

SectionSpec RandomizeSection() { return {kRandomizeSection, &Parse}; }

const RandomizeSettings& RandomizeOf(const SceneConfig& scene) {
  static const RandomizeSettings kNone;
  const auto* s = scene.sections.Get<RandomizeSettings>(kRandomizeSection);
  return s ? *s : kNone;
}

}  // namespace urlab::world
