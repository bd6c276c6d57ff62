#pragma once
// CameraVideo: writes one camera stream's frames to an MP4/WebM file through ffmpeg
// (`urlab record --video CAM OUT.mp4`), frame-exact: frame k shows the state
// n_k = floor(k / (rate * dt)) steps after the step the video began at (k / rate simulated
// seconds), the simulation waiting at that state until the camera rendered it, however fast the
// run (--max-speed) or slow the renderer, in lockstep too.
//
// Threading contract
// - Main thread: construction, OpenGate, Poll, Close, frames.
// - Physics thread, with the step mutex held: the gate's pre-step callback. It asks the camera
//   for the due state's frame (CameraStreams::WaitForStep, safe from any thread) and queues it;
//   it waits while kMaxQueued frames are queued, until Poll drains them. Every wait is bounded
//   (kMaxWait): after one expires, or after OpenGate, the simulation no longer waits (logged once).
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "urlab/world/camera_streams.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/subsystem.h"

namespace urlab::render {
class VideoWriter;
}
namespace urlab::physics {
class PhysicsEngine;
}

namespace urlab::camera {

// Makes `scene` render camera `camera` ("articulation/camera") in RGB: added to its streams
// (with rgb among its modes) and, when the global toggle is off, the only camera turned on.
// Throws InputError naming --video for a bad name or an unknown articulation.
void RequestVideoCamera(world::SceneConfig& scene, const std::string& camera);

class CameraVideo {
 public:
  static constexpr std::chrono::seconds kMaxWait{10};
  static constexpr std::size_t kMaxQueued = 64;

  // Starts ffmpeg on `path` for the rgb stream of `camera` and sets the gate on `engine`: the
  // video begins at its current step (make it while the engine is paused, before play begins,
  // for a video from the first state). Throws Error when the stream is not streamed, the
  // extension is not .mp4/.webm or ffmpeg cannot start.
  CameraVideo(world::CameraStreams& streams, const std::string& camera, const std::string& path,
              physics::PhysicsEngine& engine);
  ~CameraVideo();
  CameraVideo(const CameraVideo&) = delete;
  CameraVideo& operator=(const CameraVideo&) = delete;
  // The simulation stops waiting for frames (before stopping the physics thread). Idempotent.
  void OpenGate();
  // Writes the queued frames of the states the simulation has stepped from; false once ffmpeg
  // has failed.
  bool Poll();
  // Ends the file (after OpenGate); ffmpeg's exit status (0: complete).
  int Close();
  int frames() const;

 private:
  void BeforeStep();  // physics thread: the gate

  world::CameraStreams& streams_;
  std::size_t index_ = 0;
  std::unique_ptr<render::VideoWriter> writer_;
  // The gate (physics thread and main thread, under mu_).
  physics::PhysicsEngine& engine_;
  std::optional<std::uint64_t> callback_;
  double steps_per_frame_ = 1;  // rate * dt inverted: physics steps between frames
  std::uint64_t first_step_ = 0;
  std::uint64_t next_frame_ = 0;  // k of the next frame due
  std::mutex mu_;
  std::condition_variable drained_;
  std::deque<world::CameraFrame> queue_;
  bool open_ = false;  // the simulation no longer waits
};

// The video as a subsystem (added after the camera subsystem): BeginPlay starts it, gate set,
// before the physics thread runs, so the video holds every state from the first; EndPlay
// opens the gate before the thread stops. The host polls and closes video() itself.
class CameraVideoSubsystem : public world::Subsystem {
 public:
  CameraVideoSubsystem(world::CameraStreams& streams, std::string camera, std::string path);
  std::string_view name() const override { return "video"; }
  void BeginPlay(world::Session& session) override;
  void EndPlay(world::Session& session) override;
  CameraVideo* video() const { return video_.get(); }  // null before BeginPlay

 private:
  world::CameraStreams& streams_;
  std::string camera_, path_;
  std::unique_ptr<CameraVideo> video_;
};

}  // namespace urlab::camera
