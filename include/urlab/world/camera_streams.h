#pragma once
// CameraStreams: what other subsystems (the network's discovery and step server, the recorder's
// video) may ask of the running cameras, without knowing how they render: the list of streams
// and their latest frames, and a wait for a frame that shows a given physics step. The camera
// subsystem (src/camera) implements it; the app hands it to whoever needs it.
//
// A stream is one camera in one mode: rgb and segmentation/instance frames are B, G, R, A bytes
// per pixel (ids as IdColor in src/render/camera_renderer.h: id + 1 in B, G, R), depth frames f32
// metres, rows top-down, exactly the bytes of the stream's topic.
//
// Threading contract: every method from any thread, once the implementing subsystem has begun
// play and until it ends it.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "urlab/physics/latency.h"

namespace urlab::world {

struct CameraStreamInfo {
  std::string articulation;
  std::string camera;      // the name in the articulation's MJCF
  std::string mode;        // rgb | depth | segmentation | instance
  std::string stream;      // "{camera}" for rgb, "{camera}/{mode}" for the others
  std::string topic;       // "{articulation}/camera/{stream} " (trailing space)
  std::string meta_topic;  // "{articulation}/camera_meta/{stream}"
  // "{articulation}/camera_ucm1/{stream} " (trailing space): the same frames behind a
  // kFrameHeaderBytes header (WriteFrameHeader), published while someone subscribes to it.
  std::string header_topic;
  std::string endpoint;  // where clients connect ("" when its socket did not bind)
  int width = 0, height = 0;
  double rate = 0;  // frames per second
  // segmentation / instance: id -> name (geom names, or articulation names), in id order.
  std::vector<std::string> id_names;
};

struct CameraFrame {
  std::uint64_t frame_id = 0;       // renders of this camera so far (1 for the first)
  std::uint64_t step = 0;           // the physics step of the state it shows
  double sim_time = 0;              // the simulation time of that state
  std::int64_t state_wall_ns = 0;   // system clock when the renderer took that state
  std::int64_t render_wall_ns = 0;  // system clock when the frame was ready
  double render_ms = 0;             // time spent rendering and reading back
  int width = 0, height = 0;
  std::shared_ptr<const std::vector<std::uint8_t>> bytes;  // the wire payload
};

// The header of a frame on a stream's header_topic (docs/protocol.md, "Camera frames"): magic
// "UCM1", u32 header size (32), u64 frame_id, f64 sim_time, u64 step, little-endian.
inline constexpr std::size_t kFrameHeaderBytes = 32;
void WriteFrameHeader(std::uint8_t* out, std::uint64_t frame_id, double sim_time,
                      std::uint64_t step);

// The seed of a camera's delay jitter from the run's seed, when none is given: its own stream
// ("CAM" and the index of the camera's first stream), apart from the articulations' latency.
inline std::uint64_t CameraDelaySeed(std::uint64_t run_seed, std::size_t first_stream) {
  return physics::DeriveSeed(run_seed, 0x43414D000000ull + first_stream);
}

class CameraStreams {
 public:
  virtual ~CameraStreams() = default;
  // Whether stream `index` publishes its frames (every stream does until told otherwise). A
  // camera none of whose streams publish renders only for WaitForStep.
  virtual void SetStreaming(std::size_t index, bool on) = 0;
  virtual bool Streaming(std::size_t index) const = 0;
  virtual const std::vector<CameraStreamInfo>& Streams() const = 0;
  // Index into Streams() of `{articulation}`'s stream `stream`, -1 when none.
  int Find(const std::string& articulation, const std::string& stream) const;
  // The newest frame of stream `index`; false before the first.
  virtual bool Latest(std::size_t index, CameraFrame& out) const = 0;
  // A frame of stream `index` showing step `step` or later, rendered now if needed (whatever
  // the stream's rate); false after `timeout` or when the cameras stop.
  virtual bool WaitForStep(std::size_t index, std::uint64_t step, std::chrono::milliseconds timeout,
                           CameraFrame& out) = 0;

  // Emulated camera latency: the frames of camera `camera` ("{articulation}/{camera}", every
  // mode of it) are released `setting` after the state they show, counted in physics steps
  // (physics/latency.h: delay, jitter drawn from `seed`, never reordering, and a rate cap), to
  // its topics, to Latest and to WaitForStep alike. A frame's `step` and `sim_time` stay those of
  // the state it shows. With a delay, WaitForStep(step) returns the newest frame released by
  // `step` (false while none has been). Replaces the camera's previous setting; throws Error for
  // an unknown camera.
  virtual void SetDelay(const std::string& camera, const physics::LatencySetting& setting,
                        std::uint64_t seed) = 0;
  // The camera's setting (empty: none); throws Error for an unknown camera.
  virtual physics::LatencySetting Delay(const std::string& camera) const = 0;
};

}  // namespace urlab::world
