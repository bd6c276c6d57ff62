#pragma once
// Signals of the `urlab` process (SIGINT, SIGTERM, SIGHUP; SIGUSR1 for `run`). Installed once at
// start-up in "immediate" mode: while a command only reads, composes and compiles (nothing runs,
// nothing is being written), a signal ends the process at once with 128 + the signal number, so
// Ctrl-C is prompt even during a long MuJoCo compile on the main thread. A command that has
// something to finish (`run` playing, an output being written) switches to "graceful" mode: the
// signal is recorded for it to poll and stop cleanly, and a second signal forces the exit.
// SIGPIPE and SIGXFSZ are ignored for the whole process: a write to a closed pipe or past a file
// size limit fails with EPIPE or EFBIG like any other write error (a closed stdout or stderr
// never kills a recording; a product that cannot be written is reported and exits 1).
// Thread: the setters and getters may be called from any thread; the handlers are
// async-signal-safe.
namespace urlab::app {

// Installs the handlers (immediate mode) and ignores SIGPIPE and SIGXFSZ. Main thread, once, before
// any other thread starts.
void InstallSignalHandlers();

// Immediate (true) or graceful (false) handling of SIGINT/SIGTERM/SIGHUP.
void SetImmediateExit(bool immediate);

// The first stop signal received in graceful mode (SIGINT, SIGTERM, SIGHUP), 0 when none.
int StopSignal();

// True once after each SIGUSR1 (used by `run` to resume / pause a headless run).
bool TakePauseToggle();

// The conventional exit code of a process stopped by `signal`: 128 + signal (130 for SIGINT, 143
// for SIGTERM, 129 for SIGHUP).
constexpr int ExitCodeForSignal(int signal) { return 128 + signal; }

// Name of a stop signal ("SIGINT"), for messages.
const char* SignalName(int signal);

// Switches to graceful mode for a scope (e.g. while writing outputs) and back to immediate mode.
class GracefulScope {
 public:
  GracefulScope() { SetImmediateExit(false); }
  ~GracefulScope() { SetImmediateExit(true); }
  GracefulScope(const GracefulScope&) = delete;
  GracefulScope& operator=(const GracefulScope&) = delete;
};

}  // namespace urlab::app
