#include "viewer/frame_gate.h"

#include <spdlog/spdlog.h>

#include <cmath>

namespace urlab::viewer::internal {

namespace {

// Slack for simulation times and step counts computed from them.
constexpr double kSlack = 1e-9;

}  // namespace

void FrameGate::StartVideo(std::uint64_t first_step, double dt, int fps) {
  std::lock_guard<std::mutex> lock(mutex_);
  video_ = true;
  first_step_ = first_step;
  steps_per_frame_ = 1.0 / (static_cast<double>(fps) * dt);
  next_frame_ = 0;
}

void FrameGate::StartShot(double t) {
  std::lock_guard<std::mutex> lock(mutex_);
  shot_ = true;
  shot_at_ = t;
  shot_taken_ = false;
}

std::uint64_t FrameGate::DueStep(std::uint64_t k) const {
  return first_step_ +
         static_cast<std::uint64_t>(std::floor(static_cast<double>(k) * steps_per_frame_ + kSlack));
}

bool FrameGate::Waiting(std::uint64_t step, double time) const {
  if (open_) return false;
  if (video_ && step >= DueStep(next_frame_)) return true;
  return shot_ && !shot_taken_ && time + kSlack >= shot_at_;
}

void FrameGate::BeforeStep(std::uint64_t step, double time) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!Waiting(step, time)) return;
  if (!cv_.wait_for(lock, kMaxWait, [&] { return !Waiting(step, time); })) {
    open_ = true;
    spdlog::warn(
        "viewer: the simulation waited {} s for the viewer to capture a frame; it goes on "
        "without waiting (the video or screenshot is no longer exact)",
        kMaxWait.count());
  }
}

int FrameGate::VideoFramesDue(std::uint64_t step) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!video_) return 0;
  int n = 0;
  while (DueStep(next_frame_ + static_cast<std::uint64_t>(n)) <= step) ++n;
  return n;
}

void FrameGate::VideoWritten(std::uint64_t step) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    while (DueStep(next_frame_) <= step) ++next_frame_;
  }
  cv_.notify_all();
}

bool FrameGate::ShotDue(double time) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return shot_ && !shot_taken_ && time + kSlack >= shot_at_;
}

void FrameGate::ShotTaken() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shot_taken_ = true;
  }
  cv_.notify_all();
}

void FrameGate::Open() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    open_ = true;
  }
  cv_.notify_all();
}

std::uint64_t FrameGate::video_frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return next_frame_;
}

}  // namespace urlab::viewer::internal
