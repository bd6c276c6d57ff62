// The step server's camera operation: set_camera_streaming turns camera streams' publication on
// or off (docs/protocol.md, "Camera frames").
#include <set>

#include "net/request_fields.h"
#include "net/step_server.h"

namespace urlab::net {

using namespace request;

// {camera: bool, ...} (or the same map under `cameras`): a camera name (every mode of it), a
// stream name, or "articulation/stream"; a name that means streams of several articulations is
// refused (name it "articulation/stream"). All or nothing.
StepServer::Outcome StepServer::SetCameraStreaming(Request& r) {
  const std::vector<world::CameraStreamInfo> none;
  const auto& streams = cameras_ ? cameras_->Streams() : none;
  std::vector<std::pair<std::size_t, bool>> changes;
  for (const auto& [name, value] : CameraEntries(r.body, "true or false")) {
    const bool on = Bool(*value, name.c_str());
    std::set<std::string> owners;
    std::vector<std::size_t> found;
    for (std::size_t i = 0; i < streams.size(); ++i) {
      const world::CameraStreamInfo& s = streams[i];
      if (s.camera == name || s.stream == name || s.articulation + "/" + s.stream == name ||
          s.articulation + "/" + s.camera == name) {
        found.push_back(i);
        owners.insert(s.articulation);
      }
    }
    if (found.empty()) {
      Fail("unknown_camera", "no camera stream '" + name + "' (see hello's camera_topics)");
    }
    if (owners.size() > 1) {
      Fail("unknown_camera",
           "several articulations stream '" + name + "' (name it \"articulation/stream\")");
    }
    for (std::size_t i : found) changes.emplace_back(i, on);
  }
  for (const auto& [i, on] : changes) cameras_->SetStreaming(i, on);
  Json state = Json::object();
  for (std::size_t i = 0; i < streams.size(); ++i) {
    state[streams[i].articulation + "/" + streams[i].stream] = cameras_->Streaming(i);
  }
  return {Json{{"op", "set_camera_streaming_ok"}, {"streaming", std::move(state)}}};
}

}  // namespace urlab::net
