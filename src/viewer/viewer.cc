#include "urlab/viewer/viewer.h"

#include <fmt/format.h>

#include "urlab/core/error.h"
#include "viewer/viewer_core.h"

namespace urlab::viewer {

ViewerSubsystem::ViewerSubsystem(ViewerOptions options) : options_(std::move(options)) {}

ViewerSubsystem::~ViewerSubsystem() = default;

void ViewerSubsystem::BeginPlay(world::Session& session) {
  auto core = std::make_unique<internal::ViewerCore>(options_, manager_, playback_);
  core->SetRecorder(recorder_);
  core->Begin(session);
  core_ = std::move(core);
}

void ViewerSubsystem::Tick(world::Session& /*session*/, world::TickPhase phase) {
  if (!core_) return;
  if (phase == world::TickPhase::kInput) core_->Input();
  if (phase == world::TickPhase::kPresent) core_->Present();
}

void ViewerSubsystem::EndPlay(world::Session& /*session*/) {
  if (!core_) return;
  core_->End();
  video_error_ = core_->video_error();
  reload_request_ = core_->reload_request();
  core_.reset();
}

std::vector<world::StatusLine> ViewerSubsystem::Status() const {
  if (!core_) return {};
  return {{"frames", std::to_string(core_->frames_drawn())},
          {"fps", fmt::format("{:.1f}", core_->fps())}};
}

bool ViewerSubsystem::RequestsStop() const { return core_ && core_->stop_requested(); }

Image ViewerSubsystem::ReadPixels() { return core().ReadPixels(); }

internal::ViewerCore& ViewerSubsystem::core() {
  if (!core_) throw Error("ViewerSubsystem: not playing");
  return *core_;
}

}  // namespace urlab::viewer
