#include "urlab/core/mujoco_handlers.h"

#include <mujoco/mujoco.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <mutex>

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

void WarningHandler(const char* msg) { ReportMujocoWarning(msg ? msg : "(no message)"); }

}  // namespace

void InstallMujocoHandlers() {
  // Create spdlog's registry now, on the starting thread, before any physics thread logs: its
  // lazy initialisation inside the (uninstrumented) shared library is invisible to TSan.
  spdlog::default_logger();
  mju_user_error = &ErrorHandler;
  mju_user_warning = &WarningHandler;
}

void ReportMujocoWarning(const std::string& text) {
  spdlog::warn("MuJoCo: {}", text);
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

void SetLogLevel(const std::string& level) { spdlog::set_level(spdlog::level::from_str(level)); }

}  // namespace urlab
