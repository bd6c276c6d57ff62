#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab::app {

namespace {

// The model sizes `urlab compile` reports, in print order.
std::vector<std::pair<const char*, int>> ModelSizes(const mjModel* m) {
  return {{"nq", m->nq},           {"nv", m->nv},       {"nu", m->nu},
          {"na", m->na},           {"nbody", m->nbody}, {"njnt", m->njnt},
          {"ngeom", m->ngeom},     {"nsite", m->nsite}, {"ncam", m->ncam},
          {"nlight", m->nlight},   {"nmesh", m->nmesh}, {"ntex", m->ntex},
          {"nmat", m->nmat},       {"ntendon", m->ntendon}, {"nsensor", m->nsensor},
          {"nkey", m->nkey},       {"neq", m->neq},     {"npair", m->npair},
          {"nexclude", m->nexclude}};
}

}  // namespace

void RegisterCompileCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "compile",
      "Import a model, export it and compile it with MuJoCo from an in-memory virtual file "
      "system; print the compiled model's sizes.");
  static std::string file, save_xml, save_mjb;
  static bool json = false;
  cmd->add_option("FILE", file, "MJCF model file")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--json", json, "print the sizes as one JSON object");
  cmd->add_option("--save-xml", save_xml,
                  "also save the exported MJCF (asset paths relative to its folder; loadable "
                  "on its own)");
  cmd->add_option("--save-mjb", save_mjb, "also save the compiled model as MuJoCo binary");
  cmd->callback([&exit_code] {
    document::Document doc = mjcf::ReadFile(file);
    for (const auto& d : doc.diagnostics()) spdlog::warn("{}: {}", d.where.str(), d.message);
    mjcf::LineMap line_map;
    const std::string xml = mjcf::WriteString(doc, {}, &line_map);
    physics::ModelPtr model;
    try {
      model = physics::CompileXmlString(xml);
    } catch (const physics::CompileError& e) {
      throw Error(file + ": MuJoCo refused the model: " +
                  mjcf::ExplainCompileMessage(e.what(), line_map));
    }
    if (!save_xml.empty()) {
      mjcf::WriteFile(doc, save_xml);
      spdlog::info("saved {}", save_xml);
    }
    if (!save_mjb.empty()) {
      physics::SaveMjb(model.get(), save_mjb);
      spdlog::info("saved {}", save_mjb);
    }
    const auto sizes = ModelSizes(model.get());
    if (json) {
      nlohmann::ordered_json j;
      for (const auto& [k, v] : sizes) j[k] = v;
      std::cout << j.dump() << "\n";
    } else {
      for (const auto& [k, v] : sizes) std::cout << k << " " << v << "\n";
    }
    exit_code = 0;
  });
}

}  // namespace urlab::app
