#include "urlab/world/scene.h"

#include <spdlog/spdlog.h>
#include <stdlib.h>

#include <algorithm>
#include <filesystem>

#include "urlab/convert/mesh_assets.h"
#include "urlab/convert/prop.h"
#include "urlab/core/files.h"
#include "urlab/core/mujoco_hints.h"
#include "urlab/mjcf/bridge.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/world/scene_checks.h"

namespace urlab::world {

namespace fs = std::filesystem;

namespace {

// Compiles `doc`; a MuJoCo error is rethrown naming the source element (and its articulation).
physics::ModelPtr CompileDocument(const document::Document& doc,
                                  const std::vector<mjcf::ArticulationLayout>* layouts) {
  mjcf::LineMap map;
  const std::string xml = mjcf::WriteString(doc, {}, &map);
  physics::ModelPtr model;
  try {
    model = physics::CompileXmlString(xml);
  } catch (const physics::CompileError& e) {
    std::string msg = mjcf::ExplainCompileMessage(e.what(), map);
    if (layouts) {
      // Name the articulation whose prefix the offending element carries.
      for (const auto& art : *layouts) {
        if (msg.find("'" + art.prefix) != std::string::npos) {
          msg = art.name + ": " + msg;
          break;
        }
      }
    }
    throw physics::CompileError(msg);
  }
  return model;
}

// Reads an MJCF file and translates MuJoCo 3.x constructs; `label` prefixes error messages.
document::Document ReadBridged(const std::string& path, const std::string& label,
                               mjcf::BridgeReport* report) {
  try {
    document::Document doc = mjcf::ReadFile(path);
    *report = mjcf::ApplyBridge(doc);
    return doc;
  } catch (const InputError& e) {
    throw InputError(e.where(), label + e.message());
  }
}

// Mesh files MuJoCo 2.2.2 cannot load are converted (cached); each step is logged, warnings
// (a dropped visual mesh) are kept for the user; face orientation repairs join the bridge report
// (rule mesh.orientation).
void PrepareMeshes(document::Document& doc, const std::string& label, const std::string& cache_dir,
                   std::vector<document::Diagnostic>* warnings, mjcf::BridgeReport* bridge) {
  try {
    const convert::MeshAssetReport r = convert::PrepareMeshAssets(doc, cache_dir);
    for (const std::string& step : r.steps) spdlog::info("{}{}", label, step);
    for (const Diagnostic& w : r.warnings) {
      warnings->push_back(w);
    }
    bridge->changes.insert(bridge->changes.end(), r.bridge_changes.begin(), r.bridge_changes.end());
  } catch (const InputError& e) {
    throw InputError(e.where(), label + e.message());
  }
}

}  // namespace

void AddBridgeRuntime(const mjcf::BridgeReport& report, const std::string& prefix,
                      physics::SoftwareModelSpec* spec) {
  using B = mjcf::BridgedSensor::Kind;
  using P = physics::SoftwareSensorKind;
  static const std::map<B, P> kKinds = {{B::kJointActuatorForce, P::kJointActuatorForce},
                                        {B::kTendonActuatorForce, P::kTendonActuatorForce},
                                        {B::kKineticEnergy, P::kKineticEnergy},
                                        {B::kPotentialEnergy, P::kPotentialEnergy},
                                        {B::kInsideSite, P::kInsideSite},
                                        {B::kContact, P::kContact}};
  // Attributes naming model elements get the articulation's prefix like every name.
  static const char* kNames[] = {"site",  "objname", "geom1",    "geom2",
                                 "body1", "body2",   "subtree1", "subtree2"};
  for (const mjcf::BridgedSensor& b : report.software_sensors) {
    std::map<std::string, std::string> params = b.params;
    for (const char* n : kNames) {
      if (params.count(n) && params[n] != "world") params[n] = prefix + params[n];
    }
    spec->sensors.push_back({prefix + b.name, kKinds.at(b.kind), std::move(params)});
  }
  for (const mjcf::BridgedGravcomp& g : report.gravcomp) {
    spec->gravcomp.push_back({prefix + g.body, g.gravcomp});
  }
  for (const mjcf::BridgedDeadbandSpring& t : report.deadband_springs) {
    spec->deadband_springs.push_back({prefix + t.tendon, t.stiffness, t.lo, t.hi});
  }
  for (const mjcf::BridgedSiteEquality& e : report.site_equalities) {
    spec->site_equalities.push_back({prefix + e.equality, prefix + e.site1, prefix + e.site2});
  }
}

namespace {

void NoteBridge(const mjcf::BridgeReport& report, const std::string& label, std::string* out) {
  if (report.changes.empty()) return;
  spdlog::info(
      "{}MuJoCo 3.x constructs translated for 2.2.2 ({} change(s); `urlab validate "
      "--bridge-report` lists them)",
      label, report.changes.size());
  *out += report.Format();
}

// Writes the compiled keyframes back into the composed document's placeholder keys, so that the
// document (and the debug XML saved from it) holds the full-length keys MuJoCo needs.
void WriteKeyframeValues(document::Document& doc, const mjModel* m) {
  document::Element* section = doc.root().FirstChild("keyframe");
  if (!section) return;
  auto row = [](const mjtNum* base, int k, int n) {
    return std::vector<double>(base + static_cast<size_t>(k) * n,
                               base + static_cast<size_t>(k + 1) * n);
  };
  int k = 0;
  for (const auto& key : section->children()) {
    key->SetReals("qpos", row(m->key_qpos, k, m->nq));
    if (m->nv) key->SetReals("qvel", row(m->key_qvel, k, m->nv));
    if (m->na) key->SetReals("act", row(m->key_act, k, m->na));
    if (m->nu) key->SetReals("ctrl", row(m->key_ctrl, k, m->nu));
    if (m->nmocap) {
      key->SetReals("mpos", row(m->key_mpos, k, 3 * m->nmocap));
      key->SetReals("mquat", row(m->key_mquat, k, 4 * m->nmocap));
    }
    ++k;
  }
}

void SaveDebug(const document::Document& doc, const mjModel* m, const std::string& folder,
               const std::vector<std::string>& inputs) {
  const std::string xml = (fs::path(folder) / "scene_compiled.xml").string();
  const std::string mjb = (fs::path(folder) / "scene_compiled.mjb").string();
  RefuseOverwritingInput(xml, inputs, "save_debug_xml");
  RefuseOverwritingInput(mjb, inputs, "save_debug_xml");
  mjcf::WriteFile(doc, xml);
  WriteFileAtomic(mjb, physics::MjbBytes(m));
  spdlog::info("saved {} and {}", xml, mjb);
}

// A document the scene generated (a prop, a terrain, a launcher) as a composition input at its
// placement; it takes the scene's options. Its elements are located at the scene entry that made
// them, so a MuJoCo message about one names the scene file's line, not the generated text's.
mjcf::ArticulationInput GeneratedInput(const std::string& name, document::Document doc,
                                       const std::array<double, 3>& pos,
                                       const std::array<double, 4>& quat,
                                       const SourceLocation& where) {
  doc.root().Visit([&](document::Element& e) { e.set_location(where); });
  mjcf::ArticulationInput in;
  in.name = name;
  in.doc = std::move(doc);
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
  physics::SoftwareModelSpec software;
  std::string bridge_text;
  std::vector<document::Diagnostic> mesh_warnings;
  for (const ArticulationConfig& a : scene.articulations) {
    mjcf::ArticulationInput in;
    in.name = a.name;
    mjcf::BridgeReport report;
    in.doc = ReadBridged(a.mjcf, a.name + ": ", &report);
    PrepareMeshes(in.doc, a.name + ": ", cache_dir, &mesh_warnings, &report);
    AddBridgeRuntime(report, a.name + "_", &software);
    NoteBridge(report, a.name + ": ", &bridge_text);
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
    inputs.push_back(GeneratedInput(p.spec.name, std::move(built.doc), p.pos, p.quat, p.where));
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
    inputs.push_back(GeneratedInput(t.spec.name, std::move(built.doc), t.pos, t.quat, t.where));
  }
  // Impulse launchers: their trays and projectile pools, in world coordinates.
  for (const LauncherConfig& l : scene.launchers) {
    document::Document doc;
    try {
      doc = BuildLauncherDocument(l.spec);
    } catch (const InputError& e) {
      throw InputError(l.where, e.message());
    }
    inputs.push_back(GeneratedInput(l.spec.name, std::move(doc), {0, 0, 0}, {1, 0, 0, 0}, l.where));
  }
  mjcf::ComposeResult composed = mjcf::Compose(std::move(inputs), scene.options);
  // Scene overrides: only the fields set, over whatever the articulations gave.
  for (const auto& [k, v] : scene.options) mjcf::SetOptionAttribute(composed.doc, k, v);
  for (const auto& [k, v] : scene.size) composed.doc.Section("size").Set(k, v);
  CompiledScene out;
  out.model =
      physics::Model(CompileDocument(composed.doc, &composed.articulations), std::move(software));
  mjcf::ApplyArticulationKeyframes(composed.articulations, out.model.get());
  WriteKeyframeValues(composed.doc, out.model.get());
  out.bridge_report = std::move(bridge_text);
  if (!scene.save_debug_xml.empty()) {
    SaveDebug(composed.doc, out.model.get(), scene.save_debug_xml, SceneInputFiles(scene));
  }
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
  out.articulations = std::move(composed.articulations);
  out.diagnostics = std::move(composed.diagnostics);
  out.diagnostics.insert(out.diagnostics.end(), mesh_warnings.begin(), mesh_warnings.end());
  out.doc = std::move(composed.doc);
  return out;
}

CompiledScene BuildModel(const std::string& mjcf_path) {
  mjcf::BridgeReport report;
  document::Document doc = ReadBridged(mjcf_path, "", &report);
  CompiledScene out;
  out.diagnostics = doc.diagnostics();
  PrepareMeshes(doc, "", convert::DefaultCacheDir(), &out.diagnostics, &report);
  physics::SoftwareModelSpec software;
  AddBridgeRuntime(report, "", &software);
  out.model = physics::Model(CompileDocument(doc, nullptr), std::move(software));
  NoteBridge(report, "", &out.bridge_report);
  out.doc = std::move(doc);
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
    mjcf::ReadOptions lenient;
    lenient.check_files = false;
    lenient.check_references = false;
    try {
      for (std::string& f : mjcf::InputFiles(mjcf::ReadFile(a.mjcf, lenient))) {
        files.push_back(std::move(f));
      }
    } catch (const Error&) {
      files.push_back(a.mjcf);  // unreadable: at least the file itself
    }
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

ValidationReport Validate(const std::string& path, bool bridge_report) {
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
    mjcf::ReadOptions lenient;
    lenient.check_files = false;
    lenient.check_references = false;
    try {
      document::Document doc = mjcf::ReadFile(a.mjcf, lenient);
      sink.Append(doc.diagnostics(), label);
      mjcf::FindDuplicateNames(doc, sink, label);
      mjcf::FindMissingFiles(doc, sink, label);
      mjcf::BridgeOptions list_all;
      list_all.throw_on_refusal = false;
      mjcf::BridgeReport bridged = mjcf::ApplyBridge(doc, list_all);
      for (const InputError& e : bridged.Refusals()) sink.Add(e, label);
      if (bridge_report) {
        // Mesh repairs are bridge changes too; a mesh that cannot be read is reported by
        // FindMissingFiles above and by the composition below.
        try {
          const convert::MeshAssetReport meshes = convert::PrepareMeshAssets(doc, cache.path());
          bridged.changes.insert(bridged.changes.end(), meshes.bridge_changes.begin(),
                                 meshes.bridge_changes.end());
        } catch (const InputError&) {
        }
      }
      if (bridge_report) {
        for (const mjcf::BridgeChange& c : bridged.changes) {
          report.bridge.push_back(label + c.where.str() + ": " + mjcf::BridgeKindName(c.kind) +
                                  " [" + c.rule + "]: " + c.what);
          ++report.bridge_rules[c.rule];
        }
      }
      // References are checked after the bridge (3.x names such as frames are flattened).
      mjcf::FindDanglingReferences(doc, sink, label);
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
    // A MuJoCo compile error names the element and its file:line in its text when it can; an
    // engine error while compiling (2.2.2's compiler runs the model: "engine error: Stack
    // overflow") names nothing. Either is located at the file validated, with the hint `run`
    // prints.
    const std::string hint = MujocoHint(e.what());
    sink.Error({fs::absolute(path).lexically_normal().string(), 0},
               std::string(e.what()) + (hint.empty() ? "" : "\n  hint: " + hint));
  }
  return report;
}

}  // namespace urlab::world
