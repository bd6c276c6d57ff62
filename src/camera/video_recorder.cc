#include "urlab/camera/video_recorder.h"

#include <algorithm>
#include <cmath>

#include "render/video_writer.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/error.h"

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
                         const std::string& path)
    : streams_(streams) {
  const auto slash = camera.find('/');
  const int index = streams.Find(camera.substr(0, slash), camera.substr(slash + 1));
  if (index < 0) throw Error("--video: camera '" + camera + "' does not render");
  index_ = static_cast<std::size_t>(index);
  const world::CameraStreamInfo& info = streams.Streams()[index_];
  writer_ = std::make_unique<render::VideoWriter>(
      path, info.width, info.height, std::max(1, static_cast<int>(std::lround(info.rate))),
      render::VideoInput::kBgraTopDown);
}

CameraVideo::~CameraVideo() = default;

bool CameraVideo::Poll() {
  world::CameraFrame f;
  if (!streams_.Latest(index_, f) || f.frame_id == last_frame_) return true;
  last_frame_ = f.frame_id;
  return writer_->Write(f.bytes->data());
}

int CameraVideo::Close() { return writer_->Close(); }

int CameraVideo::frames() const { return writer_->frames(); }

}  // namespace urlab::camera
