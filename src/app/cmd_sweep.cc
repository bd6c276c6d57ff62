// `urlab sweep SWEEP.yaml`: an evaluation grid over a Dask cluster. The sweep itself is Python
// (clients/python/urlab_client/sweep.py, on Debian's python3-distributed); this subcommand runs
// it with the project's Python (app/python_env.h) and the client's folder on PYTHONPATH, passing
// every argument through (so `urlab sweep --help` is the program's own help) and this binary as the
// servers' urlab.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/python_env.h"

namespace urlab::app {

namespace {

int RunSweep(const std::vector<std::string>& args) {
  const std::string dir = PythonClientDir();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(dir + "/urlab_client/sweep.py", ec)) {
    std::cerr << "urlab: error: sweep: no Python client at " << dir
              << " (set URLAB_PYTHON_CLIENT to the folder holding urlab_client)\n";
    return 1;
  }
  const char* old = std::getenv("PYTHONPATH");
  const std::string path = dir + (old && *old ? ":" + std::string(old) : "");
  ::setenv("PYTHONPATH", path.c_str(), 1);
  // The workers start this very binary unless the sweep names another.
  std::error_code self_ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", self_ec);
  if (!self_ec && !std::getenv("URLAB_BINARY")) ::setenv("URLAB_BINARY", self.c_str(), 1);
  std::vector<std::string> argv_s = {PythonInterpreter(), "-m", "urlab_client.sweep"};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  std::cerr << "urlab: error: sweep: cannot run " << argv_s[0] << ": " << std::strerror(errno)
            << "\n";
  return 1;
}

}  // namespace

void RegisterSweepCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "Run an evaluation grid (scenes x seeds x policy commands x duration) on a Dask cluster "
      "(a LocalCluster, or a running scheduler): one recording per cell and a results table "
      "(CSV), with progress. `urlab sweep --help` describes the sweep file; the program is "
      "clients/python/urlab_client/sweep.py (python3-distributed; docs/cluster.md).");
  cmd->prefix_command();  // every argument goes to the sweep program
  cmd->set_help_flag();   // --help too
  cmd->allow_extras();
  cmd->fallthrough(false);  // not even to the app's own --help
  cmd->callback([cmd, &exit_code] { exit_code = RunSweep(cmd->remaining()); });
}

}  // namespace urlab::app
