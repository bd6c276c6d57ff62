// libFuzzer target for the scene path: a YAML scene file and an MJCF articulation, through
// world::ParseScene, the scene checks, MuJoCo's parser (mjcf::ParseFile), mjcf::Compose (mjSpec
// attachment), MuJoCo's compiler and writer, then (for what composed) world::BuildCheckedScene:
// MuJoCo compiles the composed model and the compiled-scene checks run. No physics step.
//
// Input: YAML text, optionally followed by "\n---mjcf---\n" and MJCF text. The MJCF is written
// to robot.xml in a private temporary folder next to the scene (which also holds arm.xml, a
// small valid arm), so a scene names `mjcf: robot.xml` or `mjcf: arm.xml`. Articulations whose
// MJCF lies outside that folder are not read (the input is skipped). Any input must load or fail
// with urlab::Error (InputError, CompileError, MujocoError...); never crash or leak. The scene
// sections the urlab CLI registers (viewer:, cinematic:, cameras:, network:) are registered too.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/diagnostics.h"
#include "urlab/core/error.h"
#include "urlab/mjcf/compose.h"
#include "urlab/mjcf/spec.h"
#include "urlab/net/scene_settings.h"
#include "urlab/viewer/scene_settings.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"
#include "urlab/world/scene_file.h"

namespace {

constexpr std::string_view kSeparator = "\n---mjcf---\n";
constexpr std::size_t kMaxArticulations = 8;

const std::string& Dir() {
  static const std::string dir = [] {
    urlab::fuzz::QuietStart();
    urlab::viewer::RegisterSceneSections();
    urlab::camera::RegisterSceneSections();
    urlab::net::RegisterSceneSections();
    urlab::fuzz::WriteText(urlab::fuzz::TempDir() + "/arm.xml", urlab::fuzz::kArmXml);
    return urlab::fuzz::TempDir();
  }();
  return dir;
}

bool InsideDir(const std::string& path) {
  const std::filesystem::path p = std::filesystem::path(path).lexically_normal();
  return p.parent_path() == std::filesystem::path(Dir());
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  (void)Dir();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::string& dir = Dir();
  std::string yaml = input;
  std::string mjcf = urlab::fuzz::kArmXml;
  if (const std::size_t at = input.find(kSeparator); at != std::string::npos) {
    yaml = input.substr(0, at);
    mjcf = input.substr(at + kSeparator.size());
  }
  urlab::fuzz::WriteText(dir + "/robot.xml", mjcf);
  try {
    urlab::world::SceneConfig scene = urlab::world::ParseScene(yaml, dir + "/scene.yaml");
    if (scene.articulations.size() > kMaxArticulations) return 0;
    for (const auto& a : scene.articulations) {
      if (!InsideDir(a.mjcf)) return 0;
    }
    scene.save_debug_xml.clear();  // writes nothing
    urlab::Diagnostics sink;
    urlab::world::CheckSceneConfig(scene, sink);
    // Composition as BuildScene does it, then the composed spec written out.
    std::vector<urlab::mjcf::ArticulationInput> inputs;
    for (const auto& a : scene.articulations) {
      urlab::mjcf::ArticulationInput in;
      in.name = a.name;
      in.file = a.mjcf;
      in.spec = urlab::mjcf::ParseFile(a.mjcf);
      in.placement.pos = a.pos;
      in.placement.quat = a.quat;
      in.options = a.options;
      in.include_world = a.include_world;
      inputs.push_back(std::move(in));
    }
    if (inputs.empty()) return 0;
    urlab::mjcf::ComposeResult composed = urlab::mjcf::Compose(std::move(inputs), scene.options);
    for (const auto& [k, v] : scene.size) urlab::mjcf::SetSize(composed.spec.get(), k, v);
    if (mjModel* m = mj_compile(composed.spec.get(), nullptr)) {
      mj_deleteModel(m);
      (void)urlab::mjcf::SaveXml(composed.spec.get());
    }
    if (sink.has_errors()) return 0;
    // The whole begin-play path: compose again, compile with MuJoCo, check the compiled scene.
    (void)urlab::world::BuildCheckedScene(scene);
  } catch (const urlab::Error&) {
  }
  return 0;
}
