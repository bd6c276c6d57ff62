#include "urlab/world/camera_streams.h"

namespace urlab::world {

int CameraStreams::Find(const std::string& articulation, const std::string& stream) const {
  const auto& all = Streams();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].articulation == articulation && all[i].stream == stream) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace urlab::world
