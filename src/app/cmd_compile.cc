// `urlab compile` and `urlab validate`: both build a model exactly as `urlab run` does (a single
// MJCF file is a scene of one articulation, LoadSceneOrModel), with every check begin-play runs.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/signals.h"
#include "urlab/core/files.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"

namespace urlab::app {

namespace {

// The model sizes `urlab compile` reports, in print order.
std::vector<std::pair<const char*, mjtSize>> ModelSizes(const mjModel* m) {
  return {{"nq", m->nq},
          {"nv", m->nv},
          {"nu", m->nu},
          {"na", m->na},
          {"nbody", m->nbody},
          {"njnt", m->njnt},
          {"ngeom", m->ngeom},
          {"nsite", m->nsite},
          {"ncam", m->ncam},
          {"nlight", m->nlight},
          {"nmesh", m->nmesh},
          {"ntex", m->ntex},
          {"nmat", m->nmat},
          {"ntendon", m->ntendon},
          {"nsensor", m->nsensor},
          {"nkey", m->nkey},
          {"neq", m->neq},
          {"npair", m->npair},
          {"nexclude", m->nexclude}};
}

struct CompileArgs {
  std::string file, save_xml, save_mjb;
  bool json = false;
};

int Compile(const CompileArgs& args) {
  CurrentInput() = args.file;
  const world::SceneConfig scene = world::LoadSceneOrModel(args.file);
  CheckOutputs({{args.save_xml, "--save-xml"}, {args.save_mjb, "--save-mjb"}},
               world::SceneInputFiles(scene));
  // The path `urlab run` takes: compose (a single file as articulation '<stem>'), compile, check.
  const world::CompiledScene checked = world::BuildCheckedScene(scene);
  for (const auto& d : checked.diagnostics) spdlog::warn("{}", d.str());
  if (!args.save_xml.empty() || !args.save_mjb.empty()) {
    // A single model is exported on its own, without the articulation prefix, so the saved
    // names are the user's own; a scene is exported as composed.
    world::CompiledScene own;
    if (!world::IsSceneFile(args.file)) own = world::BuildModel(args.file);
    const world::CompiledScene& out = world::IsSceneFile(args.file) ? checked : own;
    GracefulScope finish_writing;  // a signal now waits until the files are in place
    // Both or neither: each is staged next to its target, then both are put in place.
    StagedOutputs outputs;
    if (!args.save_xml.empty()) {
      // Written by MuJoCo from the spec, asset paths relative to the output folder.
      outputs.Add(
          args.save_xml,
          world::SceneXml(
              out, nullptr,
              std::filesystem::absolute(args.save_xml).parent_path().lexically_normal().string()));
    }
    if (!args.save_mjb.empty()) outputs.Add(args.save_mjb, out.model.Mjb());
    outputs.Commit();
    for (const std::string& saved : {args.save_xml, args.save_mjb}) {
      if (!saved.empty()) spdlog::info("saved {}", saved);
    }
  }
  const auto sizes = ModelSizes(checked.model.get());
  if (args.json) {
    nlohmann::ordered_json j;
    for (const auto& [k, v] : sizes) j[k] = v;
    std::cout << j.dump() << "\n";
  } else {
    for (const auto& [k, v] : sizes) std::cout << k << " " << v << "\n";
  }
  return 0;
}

struct ValidateArgs {
  std::string file;
};

int Validate(const ValidateArgs& args) {
  CurrentInput() = args.file;
  const world::ValidationReport r = world::Validate(args.file);
  for (const auto& w : r.diagnostics.warnings()) std::cout << "warning: " << w.str() << "\n";
  for (const auto& e : r.diagnostics.errors()) std::cout << "error: " << e.str() << "\n";
  if (r.ok()) {
    std::cout << args.file << ": OK";
    for (const auto& s : r.sizes) std::cout << ", " << s;
    std::cout << "\n";
  } else {
    std::cout << args.file << ": " << r.diagnostics.error_count() << " problem(s)\n";
  }
  return r.ok() ? 0 : 1;
}

}  // namespace

void RegisterCompileCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "compile",
      "Build a model (MJCF) or scene (YAML) exactly as `urlab run` does (a single MJCF file is "
      "composed as a scene of one articulation named after the file), with every check `urlab "
      "validate` runs, compile it with MuJoCo and print the compiled model's sizes. Outputs are "
      "written atomically, both or neither, and never over "
      "an "
      "input file; a device or FIFO (/dev/stdout) is written in place, a symlink through the "
      "link.");
  static CompileArgs args;
  cmd->add_option("FILE", args.file, "MJCF model file (.xml) or scene file (.yaml)")->required();
  cmd->add_flag("--json", args.json, "print the sizes as one JSON object");
  cmd->add_option("--save-xml", args.save_xml,
                  "also save the model as MJCF, written by MuJoCo (a single model keeps its own "
                  "names, a scene is saved as composed; asset paths relative to its folder; "
                  "loadable on its own)")
      ->check(OutputPath());
  cmd->add_option("--save-mjb", args.save_mjb,
                  "also save the compiled model as MuJoCo binary (same model as --save-xml; it "
                  "loads in the same MuJoCo release, e.g. the `mujoco` Python package of the "
                  "version `urlab --version` prints)")
      ->check(OutputPath());
  cmd->callback([&exit_code] { exit_code = Compile(args); });

  CLI::App* val = app.add_subcommand(
      "validate",
      "Check a scene (YAML) or MJCF file without running it or writing anything: parse every "
      "MJCF file with MuJoCo, compose and compile as `urlab run` does, run every check "
      "begin-play runs, and report every problem found with its file and line. Meshes are "
      "converted and decomposed in a temporary "
      "folder removed at the end (never in the cache). Exit code 1 when there is any error.");
  static ValidateArgs vargs;
  val->add_option("FILE", vargs.file, "scene (.yaml) or MJCF (.xml) file")->required();
  val->callback([&exit_code] { exit_code = Validate(vargs); });
}

}  // namespace urlab::app
