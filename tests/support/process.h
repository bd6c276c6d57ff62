#pragma once
// A background `urlab` (the real binary) with its stdout and stderr in a file, for tests that
// signal it or watch its output while it runs.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>

#include "mujoco_test.h"

extern char** environ;

namespace urlab::testing {

class UrlabProcess {
 public:
  using Clock = std::chrono::steady_clock;
  // `args` after the binary (shell words); the output goes to `log`.
  UrlabProcess(const std::string& args, const std::string& log) : log_(log) {
    const std::string cmd = "exec " + UrlabBinary() + " " + args + " > " + log + " 2>&1";
    const char* argv[] = {"/bin/sh", "-c", cmd.c_str(), nullptr};
    if (posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) {
      pid_ = -1;
    }
  }
  ~UrlabProcess() {
    if (pid_ > 0 && !done_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  UrlabProcess(const UrlabProcess&) = delete;
  UrlabProcess& operator=(const UrlabProcess&) = delete;

  // True once the output holds `text`; false after `limit` or when the process ended without it.
  bool WaitFor(const std::string& text, std::chrono::seconds limit = std::chrono::seconds(60)) {
    const auto start = Clock::now();
    while (output().find(text) == std::string::npos) {
      if (Clock::now() - start > limit || Ended()) return output().find(text) != std::string::npos;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return true;
  }
  // True once the process catches `sig` (its handler is installed: /proc/PID/status, SigCgt);
  // false after `limit` or when it ended. A signal sent before that would kill it by default.
  bool WaitForHandler(int sig, std::chrono::seconds limit = std::chrono::seconds(60)) {
    const auto start = Clock::now();
    while (!Catches(sig)) {
      if (Clock::now() - start > limit || Ended()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }
  // True once the process has used `cpu` of processor time (/proc/PID/stat: user + system), a
  // point in its own work whatever the machine's load; false after `limit` or when it ended.
  bool WaitForCpu(std::chrono::milliseconds cpu,
                  std::chrono::seconds limit = std::chrono::seconds(60)) {
    const auto start = Clock::now();
    while (CpuUsed() < cpu) {
      if (Clock::now() - start > limit || Ended()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }
  void Signal(int sig) { kill(pid_, sig); }
  // Exit code (128+N when killed by signal N), or -1 after `limit`.
  int Wait(std::chrono::milliseconds limit) {
    const auto start = Clock::now();
    while (!Ended()) {
      if (Clock::now() - start > limit) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return code_;
  }
  std::string output() const { return ReadTextFile(log_); }

 private:
  std::chrono::milliseconds CpuUsed() const {
    std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const std::size_t after_name = text.rfind(')');  // the name may hold spaces
    if (after_name == std::string::npos) return std::chrono::milliseconds(0);
    std::istringstream fields(text.substr(after_name + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> field; ++i) {  // fields 14 and 15: utime, stime
      if (i == 14) utime = std::stoull(field);
      if (i == 15) stime = std::stoull(field);
    }
    return std::chrono::milliseconds((utime + stime) * 1000 / sysconf(_SC_CLK_TCK));
  }
  bool Catches(int sig) const {
    std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("SigCgt:", 0) == 0) {
        return (std::stoull(line.substr(7), nullptr, 16) >> (sig - 1)) & 1u;
      }
    }
    return false;
  }
  bool Ended() {
    if (done_) return true;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return false;
    done_ = true;
    code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return true;
  }
  std::string log_;
  pid_t pid_ = -1;
  bool done_ = false;
  int code_ = -1;
};

}  // namespace urlab::testing
