#include "urlab/camera/video_recorder.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "render/video_writer.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/error.h"
#include "urlab/physics/engine.h"
#include "urlab/world/session.h"

namespace urlab::camera {

void RequestVideoCamera(world::SceneConfig& scene, const std::string& camera) {
  const auto slash = camera.find('/');
  if (slash == std::string::npos || slash == 0 || slash + 1 == camera.size()) {
    throw InputError({scene.path, 0},
                     "--video: name the camera as articulation/camera, not '" + camera + "'");
  }
  const std::string art = camera.substr(0, slash);
  bool found = false;
  for (const auto& a : scene.articulations) found = found || a.name == art;
  if (!found) throw InputError({scene.path, 0}, "--video: no articulation '" + art + "'");
  CamerasConfig& c = EditCameras(scene);
  if (!c.enabled) {
    // Streaming is off: this camera alone renders.
    c.enabled = true;
    c.cameras.clear();
    for (auto& a : scene.articulations) {
      a.all_cameras = false;
      a.cameras.clear();
    }
  }
  CameraSettings& s = c.cameras[camera];
  std::vector<std::string> modes = s.modes ? *s.modes : c.modes;
  if (std::find(modes.begin(), modes.end(), "rgb") == modes.end()) modes.push_back("rgb");
  s.modes = modes;
}

CameraVideo::CameraVideo(world::CameraStreams& streams, const std::string& camera,
                         const std::string& path, physics::PhysicsEngine& engine)
    : streams_(streams), engine_(engine) {
  const auto slash = camera.find('/');
  const int index = streams.Find(camera.substr(0, slash), camera.substr(slash + 1));
  if (index < 0) throw Error("--video: camera '" + camera + "' does not render");
  index_ = static_cast<std::size_t>(index);
  const world::CameraStreamInfo& info = streams.Streams()[index_];
  const int rate = std::max(1, static_cast<int>(std::lround(info.rate)));
  writer_ = std::make_unique<render::VideoWriter>(path, info.width, info.height, rate,
                                                  render::VideoInput::kBgraTopDown);
  // The gate: frame k at step first_step_ + floor(k * steps_per_frame_).
  steps_per_frame_ = 1.0 / (rate * engine.timestep());
  first_step_ = engine.step_count();
  callback_ = engine.AddPreStepCallback([this](const mjModel*, mjData*) { BeforeStep(); });
}

CameraVideo::~CameraVideo() { OpenGate(); }

void CameraVideo::OpenGate() {
  {
    std::lock_guard<std::mutex> hold(mu_);
    open_ = true;
  }
  drained_.notify_all();
  if (callback_) engine_.RemoveCallback(*callback_);
  callback_.reset();
}

void CameraVideo::BeforeStep() {
  {
    std::lock_guard<std::mutex> hold(mu_);
    if (open_) return;
  }
  // The frames the state about to be stepped from stands for: frame k is due at step
  // first + floor(k * steps_per_frame) (several when a step is longer than a frame).
  const std::uint64_t step = engine_.step_count();
  int due = 0;
  while (first_step_ + static_cast<std::uint64_t>(std::floor(
                           static_cast<double>(next_frame_) * steps_per_frame_ + 1e-9)) <=
         step) {
    ++next_frame_;
    ++due;
  }
  if (due == 0) return;
  world::CameraFrame f;
  const auto give_up = [&](const char* why) {
    std::lock_guard<std::mutex> hold(mu_);
    open_ = true;
    spdlog::warn("--video: {} (step {}); the run goes on without waiting for the camera", why,
                 step);
  };
  if (!streams_.WaitForStep(index_, step, kMaxWait, f)) {
    return give_up("the camera rendered no frame in 10 s");
  }
  std::unique_lock<std::mutex> hold(mu_);
  f.step = step;  // the state it shows (Poll writes it once the simulation stepped past it)
  for (int i = 0; i < due; ++i) queue_.push_back(f);
  if (queue_.size() < kMaxQueued) return;
  if (!drained_.wait_for(hold, kMaxWait, [&] { return open_ || queue_.size() < kMaxQueued / 2; })) {
    hold.unlock();
    give_up("the video writer took no frame in 10 s");
  }
}

bool CameraVideo::Poll() {
  // The queued frames, in order, of the states the simulation has stepped from. The state it
  // stands at is not in the video yet: when the run ends there, it never is (a 2 s video at 30
  // frames/s holds the 60 states at 0 .. 1.967 s, paused or lockstep alike).
  const std::uint64_t now = engine_.step_count();
  std::deque<world::CameraFrame> frames;
  {
    std::lock_guard<std::mutex> hold(mu_);
    while (!queue_.empty() && queue_.front().step < now) {
      frames.push_back(std::move(queue_.front()));
      queue_.pop_front();
    }
  }
  drained_.notify_all();
  for (const world::CameraFrame& f : frames) {
    if (!writer_->Write(f.bytes->data())) return false;
  }
  return true;
}

int CameraVideo::Close() { return writer_->Close(); }

int CameraVideo::frames() const { return writer_->frames(); }

CameraVideoSubsystem::CameraVideoSubsystem(world::CameraStreams& streams, std::string camera,
                                           std::string path)
    : streams_(streams), camera_(std::move(camera)), path_(std::move(path)) {}

void CameraVideoSubsystem::BeginPlay(world::Session& session) {
  video_ = std::make_unique<CameraVideo>(streams_, camera_, path_, session.engine());
}

void CameraVideoSubsystem::EndPlay(world::Session&) {
  if (video_) video_->OpenGate();
}

}  // namespace urlab::camera
