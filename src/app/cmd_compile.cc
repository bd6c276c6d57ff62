#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"

namespace urlab::app {

namespace {

// The model sizes `urlab compile` reports, in print order.
std::vector<std::pair<const char*, int>> ModelSizes(const mjModel* m) {
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

}  // namespace

void RegisterCompileCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "compile",
      "Import a model (MJCF) or compose a scene (YAML), export it and compile it with MuJoCo "
      "from an in-memory virtual file system; print the compiled model's sizes.");
  static std::string file, save_xml, save_mjb;
  static bool json = false;
  cmd->add_option("FILE", file, "MJCF model file (.xml) or scene file (.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--json", json, "print the sizes as one JSON object");
  cmd->add_option("--save-xml", save_xml,
                  "also save the exported MJCF (asset paths relative to its folder; loadable "
                  "on its own)");
  cmd->add_option("--save-mjb", save_mjb, "also save the compiled model as MuJoCo binary");
  cmd->callback([&exit_code] {
    world::CompiledScene compiled;
    if (world::IsSceneFile(file)) {
      compiled = world::BuildScene(world::LoadSceneFile(file));
    } else {
      compiled = world::BuildModel(file);
    }
    for (const auto& d : compiled.diagnostics) spdlog::warn("{}: {}", d.where.str(), d.message);
    if (!save_xml.empty()) {
      mjcf::WriteFile(compiled.doc, save_xml);  // asset paths relative to the output folder
      spdlog::info("saved {}", save_xml);
    }
    if (!save_mjb.empty()) {
      physics::SaveMjb(compiled.model.get(), save_mjb);
      spdlog::info("saved {}", save_mjb);
    }
    const auto sizes = ModelSizes(compiled.model.get());
    if (json) {
      nlohmann::ordered_json j;
      for (const auto& [k, v] : sizes) j[k] = v;
      std::cout << j.dump() << "\n";
    } else {
      for (const auto& [k, v] : sizes) std::cout << k << " " << v << "\n";
    }
    exit_code = 0;
  });

  CLI::App* val = app.add_subcommand(
      "validate",
      "Check a scene (YAML) or MJCF file without running it: read, compose and compile, and "
      "report every problem found with its file and line.");
  static std::string vfile;
  static bool bridge_report = false;
  val->add_option("FILE", vfile, "scene (.yaml) or MJCF (.xml) file")
      ->required()
      ->check(CLI::ExistingFile);
  val->add_flag("--bridge-report", bridge_report,
                "list every change the MuJoCo 3.x dialect bridge makes, with file and line");
  val->callback([&exit_code] {
    const world::ValidationReport r = world::Validate(vfile, bridge_report);
    for (const auto& b : r.bridge) std::cout << "bridge: " << b << "\n";
    if (bridge_report && r.bridge.empty()) std::cout << "bridge: no changes (MuJoCo 2.2.2 MJCF)\n";
    for (const auto& w : r.warnings) std::cout << "warning: " << w << "\n";
    for (const auto& e : r.errors) std::cout << "error: " << e << "\n";
    if (r.errors.empty()) {
      std::cout << vfile << ": OK";
      for (const auto& s : r.sizes) std::cout << ", " << s;
      std::cout << "\n";
    } else {
      std::cout << vfile << ": " << r.errors.size() << " problem(s)\n";
    }
    exit_code = r.errors.empty() ? 0 : 1;
  });
}

}  // namespace urlab::app
