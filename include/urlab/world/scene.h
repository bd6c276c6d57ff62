#pragma once
// Building a compiled scene: parse every articulation's MJCF into its own spec, attach them to a
// root spec with prefixes and placements (mjcf/compose.h), apply the option resolution (MuJoCo
// defaults -> the first articulation's MJCF and options -> the scene's overrides), compile with
// MuJoCo, and optionally save the debug XML/MJB. Thread: main (before the physics thread starts).
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "urlab/convert/prop.h"
#include "urlab/core/diagnostics.h"
#include "urlab/mjcf/compose.h"
#include "urlab/physics/model.h"
#include "urlab/world/launchers.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

// A Quick Convert prop in the compiled model. The viewer's collision wireframes of converted
// props (hotkey 5) draw `part_geoms` (geom group convert::kPartGroup).
struct PropLayout {
  std::string name;  // prefix "{name}_"
  convert::PropMode mode = convert::PropMode::kStatic;
  int body = -1;   // body id ("{name}_body")
  int mocap = -1;  // mocap id (mode mocap), else -1
  int visual_geom = -1;
  std::vector<int> part_geoms;  // the convex parts, in order
  int parts_from_cache = 0;     // 1 when the decomposition came from the cache
};

// A terrain's heightfield in the compiled model.
struct TerrainLayout {
  std::string name;  // prefix "{name}_"
  int geom = -1, hfield = -1;
  bool from_cache = false;  // the sampled grid came from the cache
};

struct CompiledScene {
  physics::Model model;  // what MuJoCo compiled from `spec`
  // The root spec every articulation is attached to (MuJoCo's editable model of the scene): the
  // scene's MJCF (mjcf::SaveXml) and recompiles come from it. Shared by copies of the scene. A
  // running session replaces it (Session::EditModel, ReloadKeepingState): other threads than the
  // main thread take it through Session::spec().
  std::shared_ptr<mjSpec> spec;
  // The scene's articulations in order, then its props (their layouts follow the articulations').
  std::vector<mjcf::ArticulationLayout> articulations;
  std::vector<PropLayout> props;
  std::vector<TerrainLayout> terrain;
  std::vector<LauncherLayout> launchers;  // the scene's `launchers:` in order
  std::vector<Diagnostic> diagnostics;    // warnings worth showing the user
};

// The scene as MJCF, written by MuJoCo from its spec with the options the compiled model has now
// (`model_options`, e.g. changed at run time; nullptr: the spec's own). Asset paths are absolute
// unless `relative_to` names the folder the text will be saved in.
std::string SceneXml(const CompiledScene& scene, const mjOption* model_options = nullptr,
                     const std::string& relative_to = {});
// The same from the scene's spec (a running session's: world::Session::spec()).
std::string SceneXml(const mjSpec* spec, const mjOption* model_options = nullptr,
                     const std::string& relative_to = {});

// Composes and compiles a scene. Throws InputError / CompileError with the articulation, element
// and file:line of the problem (a prop's, terrain's or launcher's at its entry in the scene file).
// Converted meshes, decompositions and height grids are cached in `cache_dir` (default:
// convert::DefaultCacheDir()).
CompiledScene BuildScene(const SceneConfig& scene, const std::string& cache_dir = {});

// A single MJCF file compiled on its own, without a prefix: parse, prepare meshes, compile. Not a
// check (LoadSceneOrModel + BuildScene is the path every command checks and runs); `urlab compile
// FILE.xml --save-xml/--save-mjb` exports this so the saved names are the user's own.
CompiledScene BuildModel(const std::string& mjcf_path);

// Every problem found in a scene or MJCF file, without stopping at the first (for
// `urlab validate`): the scene file, per MJCF file what MuJoCo's parser refuses (its first
// problem, at its line), then the scene checks begin-play runs
// (world/scene_checks.h) and, when all that was clean, composition and compilation exactly as
// `urlab run` does them (a single MJCF file is a scene of one articulation). Starts nothing and
// writes no file: a scene's save_debug_xml is ignored, and meshes are converted and decomposed
// in a temporary folder removed before it returns (so a scene with large props validates as
// slowly as its first run, whatever the user's cache holds).
struct ValidationReport {
  Diagnostics diagnostics;         // errors and warnings, each with file:line
  std::vector<std::string> sizes;  // "nq 28" ... when it compiled
  bool ok() const { return !diagnostics.has_errors(); }
};
ValidationReport Validate(const std::string& path);

// Every file a scene reads: the scene file, each articulation's MJCF, its includes and asset
// files (outputs must never overwrite one of them).
std::vector<std::string> SceneInputFiles(const SceneConfig& scene);

// True when geom `geom` of `scene`'s model is a convex part of a converted prop.
bool IsConvertedPropPart(const CompiledScene& scene, int geom);

}  // namespace urlab::world
