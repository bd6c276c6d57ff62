#include "urlab/world/scene.h"

#include <spdlog/spdlog.h>
#include <stdlib.h>

#include <algorithm>
#include <cstring>
#include <filesystem>

#include "urlab/convert/mesh_assets.h"
#include "urlab/convert/prop.h"
#include "urlab/core/files.h"
#include "urlab/core/mujoco_hints.h"
#include "urlab/mjcf/spec.h"
#include "urlab/mjcf/writer.h"
#include "urlab/world/scene_checks.h"

namespace urlab::world {

namespace fs = std::filesystem;

namespace {

// Parses an articulation's MJCF and prepares its meshes; `label` prefixes error messages.
mjcf::SpecPtr ParseArticulation(const std::string& path, const std::string& label,
                                const std::string& cache_dir, std::vector<Diagnostic>* warnings) {
  try {
    mjcf::SpecPtr spec = mjcf::ParseFile(path);
    const convert::MeshAssetReport r = convert::PrepareMeshAssets(spec.get(), path, cache_dir);
    for (const std::string& step : r.steps) spdlog::info("{}{}", label, step);
    warnings->insert(warnings->end(), r.warnings.begin(), r.warnings.end());
    return spec;
  } catch (const InputError& e) {
    throw InputError(e.where(), label + e.message());
  }
}

// Compiles `spec`; a MuJoCo error is rethrown naming the articulation whose prefix the offending
// element carries, and its file.
physics::ModelPtr CompileSpec(mjSpec* spec, const std::vector<mjcf::ArticulationLayout>& layouts,
                              const std::string& single_file = {}) {
  mjModel* m = mj_compile(spec, nullptr);
  if (m) {
    // Compiler warnings (MuJoCo reports them through the spec too).
    return physics::ModelPtr(m);
  }
  const std::string raw = mjs_getError(spec);
  std::string msg = mjcf::TidyMujocoMessage(raw);
  if (msg.empty()) msg = "MuJoCo could not compile the model";
  const int line = mjcf::LineOfMujocoMessage(raw);
  // The articulation whose prefix the offending element carries: an error in its file.
  for (const mjcf::ArticulationLayout& art : layouts) {
    if (msg.find("'" + art.prefix) != std::string::npos && !art.file.empty()) {
      throw InputError({art.file, art.line > 0 ? art.line : line}, art.name + ": " + msg);
    }
  }
  // A file MuJoCo could not open or read (a mesh, a texture): the articulation whose model (or
  // an include of it) names it, at that line.
  if (const auto open = msg.find('\''); open != std::string::npos) {
    const auto close = msg.find('\'', open + 1);
    const std::string named =
        close == std::string::npos
            ? ""
            : fs::path(msg.substr(open + 1, close - open - 1)).filename().string();
    std::vector<std::pair<std::string, std::string>> owners;  // (label, model file)
    for (const mjcf::ArticulationLayout& art : layouts) {
      if (art.line == 0) owners.emplace_back(art.name, art.file);  // not a generated one
    }
    if (!single_file.empty()) owners.emplace_back("", single_file);
    for (const auto& [name, file] : owners) {
      if (named.empty() || file.empty() || !fs::is_regular_file(file)) continue;
      for (const std::string& input : mjcf::ModelInputFiles(file)) {
        if (input.ends_with(".xml") || input == file) {
          if (const int at = mjcf::LineContaining(input, named + "\""); at > 0) {
            throw InputError({input, at}, (name.empty() ? "" : name + ": ") + msg);
          }
        }
      }
    }
  }
  if (!single_file.empty()) throw InputError({single_file, line}, msg);
  throw physics::CompileError(msg);
}

void SaveDebug(const CompiledScene& scene, const std::string& folder,
               const std::vector<std::string>& inputs) {
  const std::string xml = (fs::path(folder) / "scene_compiled.xml").string();
  const std::string mjb = (fs::path(folder) / "scene_compiled.mjb").string();
  RefuseOverwritingInput(xml, inputs, "save_debug_xml");
  RefuseOverwritingInput(mjb, inputs, "save_debug_xml");
  WriteFileAtomic(xml, SceneXml(scene, nullptr, folder));
  WriteFileAtomic(mjb, physics::MjbBytes(scene.model.get()));
  spdlog::info("saved {} and {}", xml, mjb);
}

// A document the scene generated (a prop, a terrain, a launcher) as a composition input at its
// placement; it takes the scene's options. A MuJoCo message about it names the scene file's
// line of its entry.
mjcf::ArticulationInput GeneratedInput(const std::string& name, const document::Document& doc,
                                       const std::array<double, 3>& pos,
                                       const std::array<double, 4>& quat,
                                       const SourceLocation& where) {
  mjcf::ArticulationInput in;
  in.name = name;
  try {
    in.spec = mjcf::ParseString(mjcf::WriteString(doc), where);
  } catch (const InputError& e) {
    throw InputError(where, name + ": " + e.message());
  }
  in.file = where.file;
  in.line = where.line;
  in.placement.pos = pos;
  in.placement.quat = quat;
  in.takes_scene_options = true;
  return in;
}

PropLayout PropLayoutOf(const mjModel* m, const PropConfig& p, int cache_hit) {
  PropLayout l;
  l.name = p.spec.name;
  l.mode = p.spec.mode;
  l.parts_from_cache = cache_hit;
  const std::string prefix = p.spec.name + "_";
  l.body = mj_name2id(m, mjOBJ_BODY, (prefix + convert::kPropBodyName).c_str());
  l.mocap = l.body >= 0 ? m->body_mocapid[l.body] : -1;
  l.visual_geom = mj_name2id(m, mjOBJ_GEOM, (prefix + convert::kVisualGeomName).c_str());
  for (int i = 0;; ++i) {
    const std::string name = prefix + convert::kPartGeomPrefix + std::to_string(i);
    const int g = mj_name2id(m, mjOBJ_GEOM, name.c_str());
    if (g < 0) break;
    l.part_geoms.push_back(g);
  }
  return l;
}

}  // namespace

bool IsConvertedPropPart(const CompiledScene& scene, int geom) {
  for (const PropLayout& p : scene.props) {
    if (std::find(p.part_geoms.begin(), p.part_geoms.end(), geom) != p.part_geoms.end()) {
      return true;
    }
  }
  return false;
}

std::string SceneXml(const CompiledScene& scene, const mjOption* model_options,
                     const std::string& relative_to) {
  return SceneXml(scene.spec.get(), model_options, relative_to);
}

std::string SceneXml(const mjSpec* spec, const mjOption* model_options,
                     const std::string& relative_to) {
  std::string xml;
  if (!model_options || std::memcmp(model_options, &spec->option, sizeof(mjOption)) == 0) {
    xml = mjcf::SaveXml(spec);
  } else {
    // MuJoCo writes a spec as last compiled: the options in effect go into a compiled copy,
    // every one of them written (marked authored).
    const mjcf::SpecPtr copy(mj_copySpec(spec));
    if (!copy) throw Error("MuJoCo could not copy the scene's spec");
    copy->option = *model_options;
    copy->authored.option = ~std::uint64_t{0};
    copy->authored.disableflags = ~0;
    copy->authored.enableflags = ~0;
    const physics::ModelPtr compiled(mj_compile(copy.get(), nullptr));
    if (!compiled)
      throw Error(std::string("MuJoCo could not compile the scene's copy: ") +
                  mjs_getError(copy.get()));
    xml = mjcf::SaveXml(copy.get());
  }
  return relative_to.empty() ? xml : mjcf::RelativeAssetPaths(xml, relative_to);
}

namespace {

// An error of a prop or terrain entry at the scene file's line, naming the file it concerns.
InputError AtEntry(const SourceLocation& entry, const std::string& name, const InputError& e) {
  const std::string file = e.where().str();
  return InputError(entry, name + ": " + (file.empty() ? "" : file + ": ") + e.message());
}

}  // namespace

CompiledScene BuildScene(const SceneConfig& scene, const std::string& cache) {
  const std::string cache_dir = cache.empty() ? convert::DefaultCacheDir() : cache;
  std::vector<mjcf::ArticulationInput> inputs;
  std::vector<Diagnostic> mesh_warnings;
  for (const ArticulationConfig& a : scene.articulations) {
    mjcf::ArticulationInput in;
    in.name = a.name;
    in.file = a.mjcf;
    in.spec = ParseArticulation(a.mjcf, a.name + ": ", cache_dir, &mesh_warnings);
    in.placement.pos = a.pos;
    in.placement.quat = a.quat;
    in.options = a.options;
    in.include_world = a.include_world;
    inputs.push_back(std::move(in));
  }
  // Quick Convert props, composed after the articulations like articulations of their own.
  std::vector<int> prop_cache_hits;
  for (const PropConfig& p : scene.props) {
    convert::PropDocument built;
    try {
      built = convert::BuildPropDocument(p.spec, cache_dir);
    } catch (const InputError& e) {
      throw AtEntry(p.where, p.spec.name, e);
    }
    for (const std::string& line : built.report) spdlog::info("{}: {}", p.spec.name, line);
    prop_cache_hits.push_back(built.cache_hit ? 1 : 0);
    inputs.push_back(GeneratedInput(p.spec.name, built.doc, p.pos, p.quat, p.where));
  }
  // Terrain: heightfields sampled from meshes (cached) or PNG height maps, composed last.
  std::vector<bool> terrain_cached;
  for (const TerrainConfig& t : scene.terrain) {
    convert::TerrainDocument built;
    try {
      built = convert::BuildTerrainDocument(t.spec, cache_dir);
    } catch (const InputError& e) {
      throw AtEntry(t.where, t.spec.name, e);
    }
    for (const std::string& line : built.report) spdlog::info("{}: {}", t.spec.name, line);
    terrain_cached.push_back(built.cache_hit);
    inputs.push_back(GeneratedInput(t.spec.name, built.doc, t.pos, t.quat, t.where));
  }
  // Impulse launchers: their trays and projectile pools, in world coordinates.
  for (const LauncherConfig& l : scene.launchers) {
    document::Document doc;
    try {
      doc = BuildLauncherDocument(l.spec);
    } catch (const InputError& e) {
      throw InputError(l.where, e.message());
    }
    inputs.push_back(GeneratedInput(l.spec.name, doc, {0, 0, 0}, {1, 0, 0, 0}, l.where));
  }
  mjcf::ComposeResult composed;
  try {
    composed = mjcf::Compose(std::move(inputs), scene.options);
  } catch (const InputError& e) {
    throw InputError(e.where().file.empty() ? SourceLocation{scene.path, 0} : e.where(),
                     e.message());
  }
  // Scene overrides of the sizes, over whatever the articulations gave.
  for (const auto& [k, v] : scene.size) {
    try {
      mjcf::SetSize(composed.spec.get(), k, v);
    } catch (const Error& e) {
      throw InputError({scene.path, 0}, std::string("size: ") + e.what());
    }
  }
  CompiledScene out;
  out.model = physics::Model(CompileSpec(composed.spec.get(), composed.articulations));
  mjcf::CheckAttached(out.model.get(), composed.articulations);
  for (mjcf::ArticulationLayout& art : composed.articulations)
    mjcf::LayoutOf(out.model.get(), &art);
  mjcf::PlaceKeyframes(composed.articulations, out.model.get(), composed.spec.get());
  out.spec = std::shared_ptr<mjSpec>(composed.spec.release(), mjcf::SpecDeleter());
  for (std::size_t i = 0; i < scene.props.size(); ++i) {
    out.props.push_back(PropLayoutOf(out.model.get(), scene.props[i], prop_cache_hits[i]));
  }
  for (std::size_t i = 0; i < scene.terrain.size(); ++i) {
    TerrainLayout t;
    t.name = scene.terrain[i].spec.name;
    t.geom = mj_name2id(out.model.get(), mjOBJ_GEOM, (t.name + "_geom").c_str());
    t.hfield = mj_name2id(out.model.get(), mjOBJ_HFIELD, (t.name + "_hfield").c_str());
    t.from_cache = terrain_cached[i];
    out.terrain.push_back(t);
  }
  for (const LauncherConfig& l : scene.launchers) {
    try {
      CheckTrayAboveGround(out.model.get(), l.spec);
    } catch (const InputError& e) {
      throw InputError(l.where, e.message());
    }
    out.launchers.push_back(LauncherLayoutOf(out.model.get(), l.spec));
  }
  // The articulations only (props, terrain and launchers were composed after them).
  composed.articulations.resize(scene.articulations.size());
  out.articulations = std::move(composed.articulations);
  out.diagnostics = std::move(composed.diagnostics);
  out.diagnostics.insert(out.diagnostics.end(), mesh_warnings.begin(), mesh_warnings.end());
  if (!scene.save_debug_xml.empty()) {
    SaveDebug(out, scene.save_debug_xml, SceneInputFiles(scene));
  }
  return out;
}

CompiledScene BuildModel(const std::string& mjcf_path) {
  CompiledScene out;
  mjcf::SpecPtr spec =
      ParseArticulation(mjcf_path, "", convert::DefaultCacheDir(), &out.diagnostics);
  out.model = physics::Model(CompileSpec(spec.get(), {}, mjcf_path));
  out.spec = std::shared_ptr<mjSpec>(spec.release(), mjcf::SpecDeleter());
  return out;
}

std::vector<std::string> SceneInputFiles(const SceneConfig& scene) {
  std::vector<std::string> files;
  if (!scene.path.empty()) files.push_back(scene.path);
  for (const PropConfig& p : scene.props) files.push_back(p.spec.mesh);
  for (const TerrainConfig& t : scene.terrain) {
    for (const convert::TerrainMesh& m : t.spec.meshes) files.push_back(m.file);
    if (!t.spec.png.empty()) files.push_back(t.spec.png);
  }
  for (const ArticulationConfig& a : scene.articulations) {
    for (std::string& f : mjcf::ModelInputFiles(a.mjcf)) files.push_back(std::move(f));
  }
  return files;
}

namespace {

// A fresh private folder under the system's temporary folder, removed with everything in it when
// this ends: validate's cache (converted meshes, decompositions, height grids), so that it
// writes nothing where the user keeps anything.
class ScratchDir {
 public:
  ScratchDir() {
    std::string pattern = (fs::temp_directory_path() / "urlab-validate-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) {
      throw Error("cannot create a temporary folder in " + fs::temp_directory_path().string());
    }
    path_ = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace

ValidationReport Validate(const std::string& path) {
  ValidationReport report;
  Diagnostics& sink = report.diagnostics;
  SceneConfig scene;
  try {
    scene = LoadSceneOrModel(path);
  } catch (const InputError& e) {
    sink.Add(e);
    return report;
  }
  scene.save_debug_xml.clear();  // validate writes nothing
  const ScratchDir cache;        // not even into the user's cache
  // A single MJCF file is a scene of one articulation: its findings carry no label.
  const bool is_scene = IsSceneFile(path);
  for (const ArticulationConfig& a : scene.articulations) {
    const std::string label = is_scene ? a.name + ": " : "";
    try {
      const mjcf::SpecPtr spec = mjcf::ParseFile(a.mjcf);
      for (const Diagnostic& d : mjcf::KeyframeLengthProblems(spec.get(), a.mjcf, a.name)) {
        sink.Add(d);
      }
    } catch (const InputError& e) {
      sink.Add(e, label);
    }
  }
  // Checks of the scene itself, then composition and compilation exactly as begin-play does.
  CheckSceneConfig(scene, sink);
  if (sink.has_errors()) return report;
  try {
    CompiledScene compiled = BuildScene(scene, cache.path());
    // Composition repeats each file's own findings (reported above, labelled); add only its own.
    for (const Diagnostic& d : compiled.diagnostics) {
      const bool reported = std::any_of(sink.all().begin(), sink.all().end(), [&](const auto& e) {
        return e.where.str() == d.where.str() && e.message.ends_with(d.message);
      });
      if (!reported) sink.Add(d);
    }
    CheckCompiledScene(scene, compiled, sink);
    const mjModel* m = compiled.model.get();
    // Begin-play computes the initial state (mj_forward) before anything steps: an engine error
    // there (the stack overflowing) is found here too.
    const physics::DataPtr d = physics::MakeData(m);
    mj_forward(m, d.get());
    report.sizes = {"nq " + std::to_string(m->nq), "nv " + std::to_string(m->nv),
                    "nu " + std::to_string(m->nu), "nbody " + std::to_string(m->nbody)};
  } catch (const InputError& e) {
    sink.Add(e);
  } catch (const Error& e) {
    // A MuJoCo compile error names the element, its line and (in a scene) its articulation; an
    // engine error while computing the initial state ("Stack overflow") names nothing. Either is
    // located at the file validated, with the hint `run` prints.
    const std::string hint = MujocoHint(e.what());
    sink.Error({fs::absolute(path).lexically_normal().string(), 0},
               std::string(e.what()) + (hint.empty() ? "" : "\n  hint: " + hint));
  }
  return report;
}

}  // namespace urlab::world
