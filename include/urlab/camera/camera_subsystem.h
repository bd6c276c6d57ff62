#pragma once
// CameraSubsystem: renders the MJCF cameras a scene asks for off-screen, each at its own rate
// and resolution, and streams them per docs/protocol.md: one ZeroMQ PUB per stream (a camera in one
// mode) from the scene's camera_base_port upward, topic "{art}/camera/{stream} " with the raw
// pixels, and "{art}/camera_meta/{stream}" (JSON: frame id, step, sim time, wall times, render
// time) before each frame. Send high-water marks are small and sends never wait: a slow client
// loses frames, the simulator never lags. It also serves other subsystems through
// world::CameraStreams (discovery, the step server's include_cameras, video recording).
//
// Threading contract
// - Main thread: construction, the Subsystem hooks, counters().
// - Render thread (started in BeginPlay, joined in EndPlay): the GL context, the renderer, its
//   own mjData (filled from its own latest-state subscription: the physics thread never waits
//   for it), every camera socket.
// - Any thread: the CameraStreams methods and counters(). SetDelay hands a camera's delay to the
//   render thread under the lock; the render thread holds each delayed camera's queue of frames.
#include <atomic>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/camera/scene_settings.h"
#include "urlab/world/camera_streams.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/subsystem.h"

namespace urlab::camera {

struct CameraOptions {
  CamerasConfig config;
  int base_port = 5558;                      // 0: ephemeral ports on bind_host
  std::string bind_host = "*";               // sockets bind tcp://{bind_host}:{port}
  std::string advertise_host = "127.0.0.1";  // what discovery tells clients to connect to
  bool publish = true;                       // false: render only (video, the step server)
  // Ports the scene's other sockets use (docs/protocol.md's step server default, 5559, sits inside
  // the camera range): cameras skip them.
  std::vector<int> reserved_ports;
  int render_nice = 5;  // added to the render thread's nice value
};

// The scene's `cameras:` section. The ports (base_port, reserved_ports) are the network's
// settings (`network.camera_base_port` and its endpoints): the caller sets them (the app from
// net::NetworkOf, a test or bench its own).
CameraOptions CameraOptionsFromScene(const world::SceneConfig& scene);

struct CameraCounters {
  std::uint64_t renders = 0;    // camera renders (all modes of a camera in one)
  std::uint64_t published = 0;  // frames sent
  std::uint64_t dropped = 0;    // frames a full send queue refused (a slow client)
  double render_ms_total = 0;   // time rendering and reading back
};

class CameraSubsystem : public world::Subsystem, public world::CameraStreams {
 public:
  explicit CameraSubsystem(CameraOptions options);
  ~CameraSubsystem() override;
  std::string_view name() const override { return "cameras"; }
  // Resolves the streamed cameras (InputError naming the scene file line for a camera the MJCF
  // does not have), subscribes to state, starts the render thread and waits until it has a GL
  // context and its sockets (Error when no off-screen GL works). Nothing starts when the scene
  // streams no camera or the global toggle is off.
  void BeginPlay(world::Session& session) override;
  void EndPlay(world::Session& session) override;

  const std::vector<world::CameraStreamInfo>& Streams() const override;
  bool Latest(std::size_t index, world::CameraFrame& out) const override;
  bool WaitForStep(std::size_t index, std::uint64_t step, std::chrono::milliseconds timeout,
                   world::CameraFrame& out) override;
  void SetDelay(const std::string& camera, const physics::LatencySetting& setting,
                std::uint64_t seed) override;
  physics::LatencySetting Delay(const std::string& camera) const override;

  void SetStreaming(std::size_t index, bool on) override;
  bool Streaming(std::size_t index) const override;

  CameraCounters counters() const;
  // The GL backend in use ("egl (surfaceless)", ...), "" when not rendering.
  std::string backend() const;

 private:
  struct Impl;
  CameraOptions options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace urlab::camera
