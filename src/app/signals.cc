#include "app/signals.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstring>

namespace urlab::app {

namespace {

std::atomic<int> g_stop_signal{0};
std::atomic<bool> g_immediate{true};
std::atomic<bool> g_pause_toggle{false};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free,
              "signal handlers need lock-free atomics");

void WriteStderr(const char* text) {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

extern "C" void OnStopSignal(int sig) {
  int expected = 0;
  const bool first = g_stop_signal.compare_exchange_strong(expected, sig);
  if (g_immediate.load() || !first) {
    WriteStderr(first ? "\nurlab: interrupted by " : "\nurlab: forced exit on a second ");
    WriteStderr(SignalName(sig));
    WriteStderr("\n");
    ::_exit(ExitCodeForSignal(sig));
  }
  WriteStderr("\nurlab: stopping (");
  WriteStderr(SignalName(sig));
  WriteStderr("; send it again to force)\n");
}

extern "C" void OnPauseToggle(int) { g_pause_toggle.store(true); }

void Install(int sig, void (*handler)(int)) {
  struct sigaction sa;
  std::memset(&sa, 0, sizeof(sa));
  sa.sa_handler = handler;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(sig, &sa, nullptr);
}

}  // namespace

void InstallSignalHandlers() {
  // A closed pipe (`urlab record ... | head -1`) or a file size limit is a write error to report,
  // never a silent death in the middle of writing a recording.
  for (int sig : {SIGPIPE, SIGXFSZ}) Install(sig, SIG_IGN);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) Install(sig, OnStopSignal);
  Install(SIGUSR1, OnPauseToggle);
}

void SetImmediateExit(bool immediate) {
  g_immediate.store(immediate);
  // A signal that arrived in graceful mode is not lost when switching back: it ends us now.
  if (immediate) {
    if (const int sig = g_stop_signal.load()) {
      std::fflush(nullptr);
      WriteStderr("urlab: interrupted by ");
      WriteStderr(SignalName(sig));
      WriteStderr("\n");
      ::_exit(ExitCodeForSignal(sig));
    }
  }
}

int StopSignal() { return g_stop_signal.load(); }

bool TakePauseToggle() { return g_pause_toggle.exchange(false); }

const char* SignalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "a signal";
  }
}

}  // namespace urlab::app
