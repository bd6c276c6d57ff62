#pragma once
// Subcommands of the `urlab` CLI. Each Register* adds its subcommand to the app; the callback
// runs on the main thread and returns the process exit code through `exit_code`.
namespace CLI {
class App;
}

namespace urlab::app {

void RegisterMjcfCommands(CLI::App& app, int& exit_code);
void RegisterCompileCommand(CLI::App& app, int& exit_code);
void RegisterRunCommand(CLI::App& app, int& exit_code);
void RegisterBenchCommand(CLI::App& app, int& exit_code);

}  // namespace urlab::app
