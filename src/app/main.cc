// urlab: the command-line front end of the URLab runtime.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "app/commands.h"
#include "urlab/core/error.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/core/version.h"
#include "urlab/physics/model.h"

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  // Logs go to stderr so that stdout carries only results (e.g. `compile --json`).
  spdlog::set_default_logger(spdlog::stderr_color_mt("urlab"));
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");

  CLI::App app{"URLab: MuJoCo robotics simulation runtime (scenes, control over ZeroMQ, replay)."};
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  app.set_version_flag("--version", std::string("urlab ") + urlab::kVersion + " (MuJoCo " +
                                        urlab::physics::MujocoVersion() + ")");
  app.parse_complete_callback([&] { urlab::SetLogLevel(log_level); });

  int exit_code = 0;
  urlab::app::RegisterMjcfCommands(app, exit_code);
  urlab::app::RegisterCompileCommand(app, exit_code);
  urlab::app::RegisterRunCommand(app, exit_code);
  urlab::app::RegisterBenchCommand(app, exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const urlab::Error& e) {
    std::cerr << "urlab: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "urlab: unexpected error: " << e.what() << "\n";
    return 2;
  }
  return exit_code;
}
