#pragma once
// Building a compiled scene: read every articulation's MJCF, compose them with prefixes and
// placements, apply the option resolution (MuJoCo defaults -> the first articulation's MJCF and
// options -> the scene's overrides), compile with MuJoCo, write the articulations' keyframes,
// and optionally save the debug XML/MJB. Thread: main (before the physics thread starts).
#include <string>
#include <vector>

#include "urlab/document/document.h"
#include "urlab/mjcf/compose.h"
#include "urlab/physics/model.h"
#include "urlab/physics/software_sensors.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

struct CompiledScene {
  physics::ModelPtr model;
  // Sensors 2.2.2 lacks (3.x jointactuatorfrc/tendonactuatorfrc), computed by the runtime; kept
  // registered while this lives (declared after `model`, so it is released first).
  physics::SoftwareSensorRegistration software_sensors;
  std::string bridge_report;  // what the dialect bridge changed ("" when nothing)
  std::vector<mjcf::ArticulationLayout> articulations;
  std::vector<document::Diagnostic> diagnostics;  // warnings worth showing the user
  document::Document doc;  // the (composed) document MuJoCo compiled, e.g. for --save-xml
};

// Composes and compiles a scene. Throws InputError / CompileError with the articulation, element
// and file:line of the problem.
CompiledScene BuildScene(const SceneConfig& scene);

// A single MJCF file as a scene of one articulation without a prefix (what `urlab compile FILE`
// does for an .xml): read, export, compile.
CompiledScene BuildModel(const std::string& mjcf_path);

// Every problem found in a scene or MJCF file, without stopping at the first (for
// `urlab validate`): reader errors, duplicate names, dangling references, missing files,
// diagnostics, and the compile error if the rest was clean.
struct ValidationReport {
  std::vector<std::string> errors;
  std::vector<std::string> warnings;
  std::vector<std::string> sizes;   // "nq 28" ... when it compiled
  std::vector<std::string> bridge;  // dialect bridge changes, when asked for
};
// With `bridge_report`, lists every change the MuJoCo 3.x dialect bridge makes (file and line).
ValidationReport Validate(const std::string& path, bool bridge_report = false);

}  // namespace urlab::world
