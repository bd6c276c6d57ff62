#include "net/camera_list.h"

namespace urlab::net {

nlohmann::ordered_json CameraList(const world::CameraStreams* cameras,
                                  const std::string& articulation) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  if (!cameras) return list;
  for (const world::CameraStreamInfo& s : cameras->Streams()) {
    if (s.articulation != articulation) continue;
    nlohmann::ordered_json c;
    c["name"] = s.stream;
    c["endpoint"] = s.endpoint;
    c["width"] = s.width;
    c["height"] = s.height;
    c["mode"] = s.mode;
    c["camera"] = s.camera;
    c["topic"] = s.topic;
    c["meta_topic"] = s.meta_topic;
    c["rate"] = s.rate;
    if (!s.id_names.empty()) {
      nlohmann::ordered_json ids = nlohmann::ordered_json::array();
      for (std::size_t i = 0; i < s.id_names.size(); ++i) {
        // The wire colour of id i (IdColor): i + 1 in B, G, R.
        const std::uint32_t v = static_cast<std::uint32_t>(i) + 1;
        ids.push_back({{"id", i},
                       {"name", s.id_names[i]},
                       {"color", {v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF}}});
      }
      c["ids"] = std::move(ids);
    }
    list.push_back(std::move(c));
  }
  return list;
}

}  // namespace urlab::net
