#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>

#include "app/commands.h"
#include "app/signals.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"

namespace urlab::app {

void RegisterMjcfCommands(CLI::App& app, int& exit_code) {
  CLI::App* mjcf = app.add_subcommand("mjcf", "MJCF document tools");
  mjcf->require_subcommand(1);

  CLI::App* rt = mjcf->add_subcommand(
      "roundtrip",
      "Import an MJCF file into URLab's document model and export it again. Includes are "
      "flattened; asset paths are written relative to the output file's folder, so the output "
      "loads from any working directory. The output is written atomically (missing folders are "
      "created) and may not be one of the files the model reads.");
  static std::string in, out;
  static bool absolute = false;
  rt->add_option("IN", in, "MJCF file to read")->required();
  rt->add_option("-o,--output", out,
                 "MJCF file to write (a device or FIFO such as /dev/stdout is written in place, "
                 "a symlink through the link)")
      ->required()
      ->check(OutputPath());
  rt->add_flag("--absolute-paths", absolute, "write absolute asset paths");
  rt->callback([&exit_code] {
    CurrentInput() = in;
    document::Document doc = mjcf::ReadFile(in);
    for (const auto& d : doc.diagnostics()) spdlog::warn("{}", d.str());
    CheckOutputs({{out, "-o"}}, mjcf::InputFiles(doc));
    GracefulScope finish_writing;  // a signal now waits until the file is in place
    mjcf::WriteFile(doc, out, absolute);
    spdlog::info("wrote {}", out);
    exit_code = 0;
  });
}

}  // namespace urlab::app
