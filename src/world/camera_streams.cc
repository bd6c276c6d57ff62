#include "urlab/world/camera_streams.h"

#include <cstring>

namespace urlab::world {

void WriteFrameHeader(std::uint8_t* out, std::uint64_t frame_id, double sim_time,
                      std::uint64_t step) {
  // Little-endian on every platform URLab builds for (x86-64, arm64): the bytes as they are.
  const std::uint32_t size = kFrameHeaderBytes;
  std::memcpy(out, "UCM1", 4);
  std::memcpy(out + 4, &size, 4);
  std::memcpy(out + 8, &frame_id, 8);
  std::memcpy(out + 16, &sim_time, 8);
  std::memcpy(out + 24, &step, 8);
}

int CameraStreams::Find(const std::string& articulation, const std::string& stream) const {
  const auto& all = Streams();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].articulation == articulation && all[i].stream == stream) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace urlab::world
