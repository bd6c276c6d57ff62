#include "urlab/world/scene_checks.h"

#include <string>
#include <utility>

#include "urlab/physics/latency.h"
#include "urlab/world/controller_factory.h"
#include "urlab/world/names.h"
#include "world/binding_checks.h"
#include "world/scene_section.h"

namespace urlab::world {

namespace {

// Location of a composed keyframe (the articulation's <key> element), or the articulation's.
SourceLocation KeyLocation(const CompiledScene& compiled, const std::string& scene_name,
                           const SourceLocation& fallback) {
  if (const document::Element* section = compiled.doc.FindSection("keyframe")) {
    for (const auto& k : section->children()) {
      if (k->Name() == scene_name && !k->location().file.empty()) return k->location();
    }
  }
  return fallback;
}

// The articulation's own sizes in the compiled model.
struct OwnSizes {
  std::size_t nq = 0, nv = 0, na = 0, nu = 0, nmocap = 0;
};

OwnSizes SizesOf(const mjcf::ArticulationLayout& art, const mjModel* m) {
  OwnSizes s;
  for (const std::string& jn : art.joints) {
    const int j = mj_name2id(m, mjOBJ_JOINT, jn.c_str());
    if (j < 0) continue;
    const int type = m->jnt_type[j];
    s.nq += type == mjJNT_FREE ? 7 : type == mjJNT_BALL ? 4 : 1;
    s.nv += type == mjJNT_FREE ? 6 : type == mjJNT_BALL ? 3 : 1;
  }
  for (const std::string& an : art.actuators) {
    const int a = mj_name2id(m, mjOBJ_ACTUATOR, an.c_str());
    if (a < 0) continue;
    ++s.nu;
    if (m->actuator_dyntype[a] != mjDYN_NONE) ++s.na;
  }
  s.nmocap = art.mocap_bodies.size();
  return s;
}

void CheckKeyframeLengths(const ArticulationConfig& config, const mjcf::ArticulationLayout& art,
                          const CompiledScene& compiled, Diagnostics& sink) {
  const OwnSizes own = SizesOf(art, compiled.model.get());
  for (const mjcf::ArticulationKeyframe& key : art.keyframes) {
    const struct {
      const char* attribute;
      std::size_t given;
      std::size_t expected;
      const char* size;
    } fields[] = {{"qpos", key.qpos.size(), own.nq, "nq"},
                  {"qvel", key.qvel.size(), own.nv, "nv"},
                  {"act", key.act.size(), own.na, "na"},
                  {"ctrl", key.ctrl.size(), own.nu, "nu"},
                  {"mpos", key.mocap_pos.size(), 3 * own.nmocap, "3*nmocap"},
                  {"mquat", key.mocap_quat.size(), 4 * own.nmocap, "4*nmocap"}};
    for (const auto& f : fields) {
      if (f.given == 0 || f.given == f.expected) continue;
      sink.Error(KeyLocation(compiled, key.scene_name, config.where),
                 config.name + ": keyframe '" + key.name + "': " + f.attribute + " has " +
                     std::to_string(f.given) + " value(s), the model has " + f.size + "=" +
                     std::to_string(f.expected) + " (MuJoCo needs exactly that many)");
    }
  }
}

}  // namespace

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
      CheckKeyframeLengths(a, compiled.articulations[i], compiled, sink);
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
