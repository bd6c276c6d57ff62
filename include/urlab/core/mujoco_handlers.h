#pragma once
// MuJoCo's default error handler prints and calls exit(). URLab replaces it so that an engine
// error becomes a urlab::MujocoError exception and warnings go to the log (and to any active
// WarningCapture). Call InstallMujocoHandlers() once at start-up, before other threads use
// MuJoCo; it is idempotent. The handlers themselves may run on any thread.
#include <string>
#include <vector>

namespace urlab {

// Installs the throwing error handler and the logging warning handler. Thread: main, at start-up.
// It also loads MuJoCo's engine plugins (LoadEnginePlugins).
void InstallMujocoHandlers();

// The folder of MuJoCo's engine plugins (elasticity, SDF, sensor, actuator libraries):
// $URLAB_MUJOCO_PLUGIN_DIR, else lib/mujoco_plugin of an installed URLab, else the plugins of the
// release URLab was built with; "" when none exists.
std::string EnginePluginDir();

// Registers every engine plugin of EnginePluginDir() with MuJoCo, once per process (models that
// name a plugin need it registered before they compile). Thread: any; the first call loads.
void LoadEnginePlugins();

// Routes a MuJoCo warning through URLab's handler: logged and captured. Any thread. Repeats of
// one kind of warning (the same text up to its numbers) are logged at most once a second, with
// the count of those not shown; every WarningCapture still receives each one.
void ReportMujocoWarning(const std::string& text);

// Logs the counts of warnings not shown since their kind was last logged (at the end of a run).
// Any thread.
void FlushMujocoWarningCounts();

// Collects every MuJoCo warning reported while it is alive (from any thread). Captures nest:
// each live capture sees every warning. Used by the test fixture to fail on unexpected warnings.
class WarningCapture {
 public:
  WarningCapture();
  ~WarningCapture();
  WarningCapture(const WarningCapture&) = delete;
  WarningCapture& operator=(const WarningCapture&) = delete;

  // Returns and clears the warnings captured so far. Any thread.
  std::vector<std::string> Take();

 private:
  friend void ReportMujocoWarning(const std::string& text);
  void Add(const std::string& text);
  struct Impl;
  Impl* impl_;
};

// Sets the global log level by name (trace, debug, info, warn, error, off). Thread: main.
void SetLogLevel(const std::string& level);

}  // namespace urlab
