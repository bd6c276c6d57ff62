#pragma once
// CameraVideo: writes one camera stream's frames to an MP4/WebM file through ffmpeg
// (`urlab record --video CAM OUT.mp4`), taking each new frame the camera subsystem rendered.
//
// Threading contract: one thread (the main thread's loop calls Poll); the streams it reads are
// safe from any thread.
#include <cstdint>
#include <memory>
#include <string>

#include "urlab/world/camera_streams.h"
#include "urlab/world/scene_file.h"

namespace urlab::render {
class VideoWriter;
}

namespace urlab::camera {

// Makes `scene` render camera `camera` ("articulation/camera") in RGB: added to its streams
// (with rgb among its modes) and, when the global toggle is off, the only camera turned on.
// Throws InputError naming --video for a bad name or an unknown articulation.
void RequestVideoCamera(world::SceneConfig& scene, const std::string& camera);

class CameraVideo {
 public:
  // Starts ffmpeg on `path` for the rgb stream of `camera`; throws Error when the stream is not
  // streamed, the extension is not .mp4/.webm or ffmpeg cannot start.
  CameraVideo(world::CameraStreams& streams, const std::string& camera, const std::string& path);
  ~CameraVideo();
  CameraVideo(const CameraVideo&) = delete;
  CameraVideo& operator=(const CameraVideo&) = delete;
  // Writes the newest frame when it is new; false once ffmpeg has failed.
  bool Poll();
  // Ends the file; ffmpeg's exit status (0: complete).
  int Close();
  int frames() const;

 private:
  world::CameraStreams& streams_;
  std::size_t index_ = 0;
  std::uint64_t last_frame_ = 0;
  std::unique_ptr<render::VideoWriter> writer_;
};

}  // namespace urlab::camera
