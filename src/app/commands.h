#pragma once
// Subcommands of the `urlab` CLI. Each Register* adds its subcommand to the app; the callback
// runs on the main thread and returns the process exit code through `exit_code`.
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
class Validator;
}  // namespace CLI
namespace urlab::viewer {
struct ViewerOptions;
}  // namespace urlab::viewer

namespace urlab::app {

void RegisterMjcfCommands(CLI::App& app, int& exit_code);
void RegisterCompileCommand(CLI::App& app, int& exit_code);
void RegisterRunCommand(CLI::App& app, int& exit_code);
void RegisterViewCommand(CLI::App& app, int& exit_code);
void RegisterRecordCommand(CLI::App& app, int& exit_code);
void RegisterReplayCommand(CLI::App& app, int& exit_code);
void RegisterRenderCommand(CLI::App& app, int& exit_code);
void RegisterBenchCommand(CLI::App& app, int& exit_code);
// `bench batch` (cmd_bench_batch.cc), added by RegisterBenchCommand.
void RegisterBenchBatchCommand(CLI::App& bench, int& exit_code);
void RegisterConvertCommand(CLI::App& app, int& exit_code);
void RegisterSweepCommand(CLI::App& app, int& exit_code);

// The file the running command works on: main() names it when an error arrives without a
// location of its own. Main thread.
std::string& CurrentInput();

// The check of every option naming an output file: "" is a usage error (it would write nothing
// and say nothing), not "no output".
const CLI::Validator& OutputPath();

// Refuses (InputError) an output path that is one of `inputs`; "" outputs are ignored.
void CheckOutputs(const std::vector<std::pair<std::string, std::string>>& outputs,
                  const std::vector<std::string>& inputs);

// The viewer's files: `view` opens `file` (a scene, an MJCF model or a recording) and then each
// file the window asks for (Reload, a file dropped on it); a file that fails to open is reported
// and the previous one opens again (cmd_run.cc).
int ViewFiles(const std::string& file, const viewer::ViewerOptions& viewer);
// Plays the recording `file` in the viewer with its replay timeline, as `replay FILE --view`
// does; `reopen` gets the file the window asks for next, "" when none (cmd_replay.cc).
int ViewRecording(const std::string& file, const viewer::ViewerOptions& viewer,
                  std::string* reopen);
// True when `path` names a recording (.urrec, or the .urrec.part of an unfinished one).
bool IsRecordingPath(const std::string& path);

// The viewer's render quality options (--shadows/--no-shadows, --reflections, --skybox,
// --render-scale), for `view`, `run --view` and `replay --view`.
void AddRenderQualityOptions(CLI::App* cmd, viewer::ViewerOptions& options);

}  // namespace urlab::app
