// The step server's camera latency operation (docs/protocol.md, "Emulated latency"):
// set_camera_delay hands each named camera's delay to the camera subsystem
// (world::CameraStreams::SetDelay); what a setting means is physics/latency.h.
#include <string>

#include "net/latency_request.h"
#include "net/request_fields.h"
#include "net/step_server.h"
#include "urlab/core/error.h"
#include "urlab/physics/latency.h"

namespace urlab::net {

using namespace request;

namespace {

// "{articulation}/{camera}", or a camera name that only one articulation streams; *index is
// the camera's first stream.
std::string CameraKey(const world::CameraStreams& cameras, const std::string& name,
                      std::size_t* index) {
  std::string found;
  const auto& streams = cameras.Streams();
  for (std::size_t i = 0; i < streams.size(); ++i) {
    const auto& info = streams[i];
    const std::string key = info.articulation + "/" + info.camera;
    if (key == name) {
      *index = i;
      return key;
    }
    if (info.camera == name && found != key) {
      *index = i;
      if (!found.empty()) {
        Fail("unknown_camera", "camera '" + name + "' is streamed by more than one articulation (" +
                                   found + ", " + key + "): name it \"articulation/camera\"");
      }
      found = key;
    }
  }
  if (found.empty()) Fail("unknown_camera", "no streamed camera '" + name + "'");
  return found;
}

}  // namespace

StepServer::Outcome StepServer::SetCameraDelay(Request& r) {
  if (!cameras_ || cameras_->Streams().empty()) {
    Fail("unknown_camera", "this scene streams no camera (the scene's cameras: section)");
  }
  // Every entry is checked before any is applied.
  struct Entry {
    std::string key;
    physics::LatencySetting setting;
    std::uint64_t seed;
  };
  std::vector<Entry> entries;
  for (const auto& [name, value] : CameraEntries(r.body, "delay settings")) {
    std::size_t index = 0;
    const std::string key = CameraKey(*cameras_, name, &index);
    std::optional<std::uint64_t> seed;
    const physics::LatencySetting s = LatencySettingFromRequest(*value, "cameras." + name, &seed);
    if (const std::string problem = physics::CheckLatency(s, session_.engine().timestep());
        !problem.empty()) {
      Fail("bad_value", "cameras." + name + ": " + problem);
    }
    // Each camera draws its own jitter from the run's seed unless the request gives one.
    entries.push_back(
        {key, s, seed ? *seed : world::CameraDelaySeed(session_.latency_seed(), index)});
  }
  if (entries.empty()) Fail("missing_field", "name at least one camera and its delay setting");
  Json reply{{"op", "set_camera_delay_ok"}, {"cameras", Json::object()}};
  for (const Entry& e : entries) {
    cameras_->SetDelay(e.key, e.setting, e.seed);
    Json fields = Json::object();
    for (const auto& [k, v] : physics::LatencyFields(cameras_->Delay(e.key))) fields[k] = v;
    fields["seed"] = e.seed;
    reply["cameras"][e.key] = std::move(fields);
  }
  return {reply};
}

}  // namespace urlab::net
