#include "urlab/world/scene_checks.h"

#include <string>
#include <utility>

#include "urlab/physics/latency.h"
#include "urlab/world/controller_factory.h"
#include "urlab/world/names.h"
#include "world/binding_checks.h"
#include "world/scene_section.h"

namespace urlab::world {

void CheckSceneConfig(const SceneConfig& scene, Diagnostics& sink) {
  for (const ArticulationConfig& a : scene.articulations) {
    // Where one prefix starts another, prefix binding would be ambiguous ("arm_" would also own
    // "arm_left_..."): refuse with the place to fix.
    for (const ArticulationConfig& b : scene.articulations) {
      if (&a != &b && (b.name + "_").starts_with(a.name + "_")) {
        sink.Error(b.where, "articulation names '" + a.name + "' and '" + b.name +
                                "' overlap (prefix '" + a.name + "_' would also own '" + b.name +
                                "_' elements); rename one");
      }
    }
    // A launcher whose prefix an articulation's would own (its projectiles would be bound as
    // that articulation's joints).
    for (const LauncherConfig& l : scene.launchers) {
      if ((l.spec.name + "_").starts_with(a.name + "_")) {
        sink.Error(l.where, "launcher name '" + l.spec.name + "' starts with articulation '" +
                                a.name +
                                "_' (that articulation would own its projectiles); "
                                "rename the launcher");
      }
    }
    if (a.hold_keyframe && a.keyframe.empty()) {
      sink.Error(a.where, a.name + ": hold_keyframe needs an initial 'keyframe'");
    }
  }
}

void CheckCompiledScene(const SceneConfig& scene, const CompiledScene& compiled,
                        Diagnostics& sink) {
  const mjModel* m = compiled.model.get();
  if (!m) return;
  for (std::size_t i = 0; i < scene.articulations.size(); ++i) {
    const ArticulationConfig& a = scene.articulations[i];
    const std::string prefix =
        i < compiled.articulations.size() ? compiled.articulations[i].prefix : a.name + "_";
    if (!a.keyframe.empty()) {
      try {
        if (FindNamed(m, mjOBJ_KEY, prefix, a.keyframe) < 0) {
          sink.Error(a.where, a.name + ": keyframe '" + a.keyframe + "' is not in " + a.mjcf);
        }
      } catch (const Error& e) {
        sink.Error(a.where, a.name + ": " + e.what());
      }
    }
    if (i < compiled.articulations.size()) {
      CheckArticulationBindings(scene, a, compiled.articulations[i], m, sink);
    }
    CheckController(a, m, prefix, sink);
    // Emulated latency: its ticks at this timestep are bounded (physics/latency.h).
    for (const auto& [channel, setting] : {std::pair{"control", &a.latency.control},
                                           std::pair{"observation", &a.latency.observation}}) {
      if (const std::string problem = physics::CheckLatency(*setting, m->opt.timestep);
          !problem.empty()) {
        sink.Error(a.where, a.name + ".latency." + channel + ": " + problem);
      }
    }
  }
  // What the subsystems' sections name (the cameras of `cameras.streams`, ...).
  CheckSceneSections(scene, compiled, sink);
}

CompiledScene BuildCheckedScene(const SceneConfig& scene) {
  Diagnostics problems;
  CheckSceneConfig(scene, problems);
  problems.ThrowIfErrors();
  CompiledScene compiled = BuildScene(scene);
  CheckCompiledScene(scene, compiled, problems);
  problems.ThrowIfErrors();
  return compiled;
}

}  // namespace urlab::world
