#include "urlab/world/scene.h"

#include <spdlog/spdlog.h>

#include <filesystem>

#include "urlab/mjcf/bridge.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"

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

void AddSoftwareSensors(const mjcf::BridgeReport& report, const std::string& prefix,
                        std::vector<physics::SoftwareSensorSpec>* specs) {
  for (const mjcf::BridgedSensor& b : report.software_sensors) {
    specs->push_back({prefix + b.name, b.kind == mjcf::BridgedSensor::Kind::kJointActuatorForce
                                           ? physics::SoftwareSensorKind::kJointActuatorForce
                                           : physics::SoftwareSensorKind::kTendonActuatorForce});
  }
}

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

void SaveDebug(const document::Document& doc, const mjModel* m, const std::string& folder) {
  fs::create_directories(folder);
  const std::string xml = (fs::path(folder) / "scene_compiled.xml").string();
  const std::string mjb = (fs::path(folder) / "scene_compiled.mjb").string();
  mjcf::WriteFile(doc, xml);
  physics::SaveMjb(m, mjb);
  spdlog::info("saved {} and {}", xml, mjb);
}

}  // namespace

CompiledScene BuildScene(const SceneConfig& scene) {
  std::vector<mjcf::ArticulationInput> inputs;
  std::vector<physics::SoftwareSensorSpec> software;
  std::string bridge_text;
  for (const ArticulationConfig& a : scene.articulations) {
    mjcf::ArticulationInput in;
    in.name = a.name;
    mjcf::BridgeReport report;
    in.doc = ReadBridged(a.mjcf, a.name + ": ", &report);
    AddSoftwareSensors(report, a.name + "_", &software);
    NoteBridge(report, a.name + ": ", &bridge_text);
    in.placement.pos = a.pos;
    in.placement.quat = a.quat;
    in.options = a.options;
    in.include_world = a.include_world;
    inputs.push_back(std::move(in));
  }
  mjcf::ComposeResult composed = mjcf::Compose(std::move(inputs));
  // Scene overrides: only the fields set, over whatever the articulations gave.
  for (const auto& [k, v] : scene.options) mjcf::SetOptionAttribute(composed.doc, k, v);
  for (const auto& [k, v] : scene.size) composed.doc.Section("size").Set(k, v);
  CompiledScene out;
  out.model = CompileDocument(composed.doc, &composed.articulations);
  mjcf::ApplyArticulationKeyframes(composed.articulations, out.model.get());
  WriteKeyframeValues(composed.doc, out.model.get());
  out.software_sensors = physics::RegisterSoftwareSensors(out.model.get(), software);
  out.bridge_report = std::move(bridge_text);
  for (const ArticulationConfig& a : scene.articulations) {
    if (a.keyframe.empty()) continue;
    const std::string key = a.name + "_" + a.keyframe;
    if (mj_name2id(out.model.get(), mjOBJ_KEY, key.c_str()) < 0) {
      throw InputError(a.where, a.name + ": keyframe '" + a.keyframe + "' is not in " + a.mjcf);
    }
  }
  if (!scene.save_debug_xml.empty()) SaveDebug(composed.doc, out.model.get(), scene.save_debug_xml);
  out.articulations = std::move(composed.articulations);
  out.diagnostics = std::move(composed.diagnostics);
  out.doc = std::move(composed.doc);
  return out;
}

CompiledScene BuildModel(const std::string& mjcf_path) {
  mjcf::BridgeReport report;
  document::Document doc = ReadBridged(mjcf_path, "", &report);
  CompiledScene out;
  out.diagnostics = doc.diagnostics();
  out.model = CompileDocument(doc, nullptr);
  std::vector<physics::SoftwareSensorSpec> software;
  AddSoftwareSensors(report, "", &software);
  out.software_sensors = physics::RegisterSoftwareSensors(out.model.get(), software);
  NoteBridge(report, "", &out.bridge_report);
  out.doc = std::move(doc);
  return out;
}

ValidationReport Validate(const std::string& path, bool bridge_report) {
  ValidationReport report;
  std::vector<std::string> mjcf_files;
  SceneConfig scene;
  const bool is_scene = IsSceneFile(path);
  try {
    if (is_scene) {
      scene = LoadSceneFile(path);
      for (const auto& a : scene.articulations) mjcf_files.push_back(a.mjcf);
    } else {
      mjcf_files.push_back(path);
    }
  } catch (const Error& e) {
    report.errors.push_back(e.what());
    return report;
  }
  for (size_t i = 0; i < mjcf_files.size(); ++i) {
    const std::string label = is_scene ? scene.articulations[i].name + ": " : "";
    mjcf::ReadOptions lenient;
    lenient.check_files = false;
    lenient.check_references = false;
    try {
      document::Document doc = mjcf::ReadFile(mjcf_files[i], lenient);
      for (const auto& d : doc.diagnostics()) {
        report.warnings.push_back(label + d.where.str() + ": " + d.message);
      }
      for (auto* finder : {&mjcf::FindDuplicateNames, &mjcf::FindMissingFiles}) {
        for (const InputError& e : finder(doc)) report.errors.push_back(label + e.what());
      }
      mjcf::BridgeOptions list_all;
      list_all.throw_on_refusal = false;
      const mjcf::BridgeReport bridged = mjcf::ApplyBridge(doc, list_all);
      for (const InputError& e : bridged.Refusals()) report.errors.push_back(label + e.what());
      if (bridge_report) {
        for (const mjcf::BridgeChange& c : bridged.changes) {
          report.bridge.push_back(label + c.where.str() + ": " + mjcf::BridgeKindName(c.kind) +
                                  ": " + c.what);
        }
      }
      // References are checked after the bridge (3.x names such as frames are flattened).
      for (const InputError& e : mjcf::FindDanglingReferences(doc)) {
        report.errors.push_back(label + e.what());
      }
    } catch (const Error& e) {
      report.errors.push_back(label + e.what());
    }
  }
  if (!report.errors.empty()) return report;
  try {
    CompiledScene compiled = is_scene ? BuildScene(scene) : BuildModel(path);
    for (const auto& d : compiled.diagnostics) {
      if (!is_scene) continue;  // already reported per file above
      report.warnings.push_back(d.where.str() + ": " + d.message);
    }
    const mjModel* m = compiled.model.get();
    report.sizes = {"nq " + std::to_string(m->nq), "nv " + std::to_string(m->nv),
                    "nu " + std::to_string(m->nu), "nbody " + std::to_string(m->nbody)};
  } catch (const Error& e) {
    report.errors.push_back(e.what());
  }
  return report;
}

}  // namespace urlab::world
