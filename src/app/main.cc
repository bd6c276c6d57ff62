// urlab: the command-line front end of the URLab runtime.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <new>

#include "app/commands.h"
#include "app/signals.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/error.h"
#include "urlab/core/files.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/core/mujoco_hints.h"
#include "urlab/core/version.h"
#include "urlab/net/scene_settings.h"
#include "urlab/physics/model.h"
#include "urlab/viewer/scene_settings.h"

namespace urlab::app {

std::string& CurrentInput() {
  static std::string file;
  return file;
}

const CLI::Validator& OutputPath() {
  static const CLI::Validator check(
      [](std::string& path) -> std::string {
        return path.empty() ? "an output file name may not be empty" : std::string();
      },
      "PATH");
  return check;
}

void CheckOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::string>& inputs) {
  for (const auto& [path, what] : outputs) {
    if (!path.empty()) RefuseOverwritingInput(path, inputs, what);
  }
}

}  // namespace urlab::app

int main(int argc, char** argv) {
  urlab::app::InstallSignalHandlers();
  urlab::InstallMujocoHandlers();
  // Logs go to stderr so that stdout carries only results (e.g. `compile --json`).
  spdlog::set_default_logger(spdlog::stderr_color_mt("urlab"));
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  // The scene sections subsystems own, registered from the top (src/world/scene_section.h):
  // world never includes the modules above it.
  urlab::viewer::RegisterSceneSections();
  urlab::camera::RegisterSceneSections();
  urlab::net::RegisterSceneSections();

  CLI::App app{"URLab: MuJoCo robotics simulation runtime (scenes, control over ZeroMQ, replay)."};
  app.require_subcommand(1);
  // Global options (--log-level) are also accepted after the subcommand (every subcommand
  // inherits this; each falls through to its parents for options it does not know).
  app.fallthrough();
  app.footer(
      "Global options may also follow the subcommand. Exit codes: 0 success, 1 bad input or a "
      "failed run or output (the message names the file and line, or the output and what was "
      "kept), 2 internal error, 105-109 bad command line, 128+N stopped by signal N (130 "
      "Ctrl-C, 143 SIGTERM, 129 SIGHUP).");
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
  urlab::app::RegisterViewCommand(app, exit_code);
  urlab::app::RegisterRecordCommand(app, exit_code);
  urlab::app::RegisterReplayCommand(app, exit_code);
  urlab::app::RegisterRenderCommand(app, exit_code);
  urlab::app::RegisterBenchCommand(app, exit_code);
  urlab::app::RegisterConvertCommand(app, exit_code);
  urlab::app::RegisterSweepCommand(app, exit_code);

  // Every error names a place: its own location, else the path it concerns, else the input the
  // command was working on.
  const auto where = [] {
    const std::string& f = urlab::app::CurrentInput();
    return f.empty() ? std::string() : f + ": ";
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const urlab::InputError& e) {
    std::cerr << "urlab: error: " << e.what() << "\n";
    return 1;
  } catch (const urlab::Error& e) {
    // Our other errors mostly carry their context (MuJoCo compile errors name the element and
    // its file:line); name the input when the message does not start with a place.
    const std::string what = e.what();
    const std::string& input = urlab::app::CurrentInput();
    const bool located = what.find(": ") != std::string::npos &&
                         (what.starts_with("/") || (!input.empty() && what.starts_with(input)));
    std::cerr << "urlab: error: " << (located ? "" : where()) << what << "\n";
    if (const std::string hint = urlab::MujocoHint(what); !hint.empty()) {
      std::cerr << "  hint: " << hint << "\n";
    }
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::cerr << "urlab: error: " << e.path1().string() << ": " << e.code().message() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "urlab: error: " << where() << "out of memory (is a size field too large?)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "urlab: error: " << where() << "internal error: " << e.what()
              << " (please report it)\n";
    return 2;
  }
  // Results printed on a closed pipe or a full disk are lost: an ordinary error (SIGPIPE is
  // ignored, so a write to a closed stdout fails here instead of killing the process earlier).
  std::cout.flush();
  errno = 0;
  const bool flush_failed = std::fflush(stdout) != 0;
  const int err = flush_failed ? errno : 0;
  if (flush_failed || std::ferror(stdout) || !std::cout) {
    std::cerr << "urlab: error: cannot write to standard output"
              << (err ? std::string(": ") + std::strerror(err) : std::string())
              << "; what it printed is lost (files the command wrote are complete)\n";
    if (exit_code == 0) exit_code = 1;
  }
  return exit_code;
}
