#include "urlab/core/mujoco_handlers.h"

#include <dlfcn.h>
#include <mujoco/mujoco.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

#include "core/warning_limiter.h"
#include "urlab/core/error.h"

namespace urlab {

struct WarningCapture::Impl {
  std::mutex mutex;
  std::vector<std::string> warnings;
};

namespace {

std::mutex& CapturesMutex() {
  static std::mutex m;
  return m;
}
std::vector<WarningCapture*>& Captures() {
  static std::vector<WarningCapture*> v;
  return v;
}

void ErrorHandler(const char* msg) {
  // Unwinds through MuJoCo's C frames (built with unwind tables on Debian's x86_64/arm64).
  throw MujocoError(std::string("MuJoCo error: ") + (msg ? msg : "(no message)"));
}

// Repeated warnings (a diverging model warns every step) are logged at most once a second per
// kind, with the count of those left out; captures still see every one.
std::mutex& LimiterMutex() {
  static std::mutex m;
  return m;
}
internal::WarningLimiter& Limiter() {
  static internal::WarningLimiter limiter;
  return limiter;
}

void WarningHandler(const char* msg) { ReportMujocoWarning(msg ? msg : "(no message)"); }

}  // namespace

void InstallMujocoHandlers() {
  // Create spdlog's registry now, on the starting thread, before any physics thread logs: its
  // lazy initialisation inside the (uninstrumented) shared library is invisible to TSan.
  spdlog::default_logger();
  mju_user_error = &ErrorHandler;
  mju_user_warning = &WarningHandler;
  LoadEnginePlugins();
}

std::string EnginePluginDir() {
  namespace fs = std::filesystem;
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("URLAB_MUJOCO_PLUGIN_DIR"); env && *env) {
    return env;  // the user's choice, even when it does not exist (then nothing is loaded)
  }
  // Beside an installed URLab: <prefix>/lib/mujoco_plugin, found from this code's own file.
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(&EnginePluginDir), &info) && info.dli_fname) {
    const fs::path self = fs::weakly_canonical(info.dli_fname);
    candidates.push_back((self.parent_path().parent_path() / "lib" / "mujoco_plugin").string());
    candidates.push_back((self.parent_path() / "mujoco_plugin").string());
  }
  candidates.push_back(URLAB_MUJOCO_PLUGIN_DIR);  // the release it was built with
  for (const std::string& c : candidates) {
    std::error_code ec;
    if (!c.empty() && fs::is_directory(c, ec)) return c;
  }
  return "";
}

void LoadEnginePlugins() {
  static std::once_flag once;
  std::call_once(once, [] {
    const std::string dir = EnginePluginDir();
    if (dir.empty()) {
      spdlog::debug("MuJoCo engine plugins: no plugin folder found");
      return;
    }
    mj_loadAllPluginLibraries(dir.c_str(), nullptr);
    spdlog::debug("MuJoCo engine plugins: {} registered from {}", mjp_pluginCount(), dir);
  });
}

void ReportMujocoWarning(const std::string& text) {
  std::uint64_t skipped = 0;
  bool log = false;
  {
    std::lock_guard<std::mutex> lock(LimiterMutex());
    log = Limiter().Admit(text, internal::WarningLimiter::Clock::now(), &skipped);
  }
  if (log && skipped > 0) {
    spdlog::warn("MuJoCo: {} ({} more like it in the last second, not shown)", text, skipped);
  } else if (log) {
    spdlog::warn("MuJoCo: {}", text);
  }
  std::lock_guard<std::mutex> lock(CapturesMutex());
  for (WarningCapture* c : Captures()) c->Add(text);
}

WarningCapture::WarningCapture() : impl_(new Impl) {
  std::lock_guard<std::mutex> lock(CapturesMutex());
  Captures().push_back(this);
}

WarningCapture::~WarningCapture() {
  {
    std::lock_guard<std::mutex> lock(CapturesMutex());
    auto& v = Captures();
    v.erase(std::remove(v.begin(), v.end(), this), v.end());
  }
  delete impl_;
}

std::vector<std::string> WarningCapture::Take() {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::vector<std::string> out;
  out.swap(impl_->warnings);
  return out;
}

void WarningCapture::Add(const std::string& text) {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->warnings.push_back(text);
}

void FlushMujocoWarningCounts() {
  std::vector<std::pair<std::string, std::uint64_t>> skipped;
  {
    std::lock_guard<std::mutex> lock(LimiterMutex());
    skipped = Limiter().TakeSkipped();
  }
  for (const auto& [text, n] : skipped) {
    spdlog::warn("MuJoCo: {} more warning(s) like \"{}\" were not shown", n, text);
  }
}

void SetLogLevel(const std::string& level) { spdlog::set_level(spdlog::level::from_str(level)); }

}  // namespace urlab
