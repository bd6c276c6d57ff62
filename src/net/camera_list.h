#pragma once
// The cameras one articulation streams, as discovery's `camera_list` and hello's `camera_topics`
// list them: name (the stream: "{cam}" or "{cam}/{mode}"), endpoint, width, height, mode, topic,
// meta_topic, rate, and for segmentation and instance streams the id -> colour table (`ids`:
// id, name, colour as [B, G, R]). Thread: any (reads the immutable stream list).
#include <nlohmann/json.hpp>
#include <string>

#include "urlab/world/camera_streams.h"

namespace urlab::net {

// An empty list when `cameras` is nullptr.
nlohmann::ordered_json CameraList(const world::CameraStreams* cameras,
                                  const std::string& articulation);

}  // namespace urlab::net
