// libFuzzer target for recording files (.urrec): the file header, chunk headers, the header
// chunk's JSON and tables, zstd payloads and every record decoder, through RecordingReader (both
// strict and keeping the readable prefix) and ReadChunk on every chunk. Any input must read or
// fail with urlab::Error (RecordingError); never crash, leak or allocate without bound.
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "fuzz_support.h"
#include "urlab/core/error.h"
#include "urlab/replay/recording.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = [] {
    urlab::fuzz::QuietStart();
    return urlab::fuzz::TempDir() + "/input.urrec";
  }();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  for (bool partial : {false, true}) {
    try {
      const urlab::replay::RecordingReader r =
          urlab::replay::RecordingReader::Open(path, {partial});
      for (std::size_t i = 0; i < r.chunks().size(); ++i) {
        try {
          (void)r.ReadChunk(i);
        } catch (const urlab::Error&) {
        }
      }
      (void)r.frame_count();
      (void)r.ChunkAt(0.5);
    } catch (const urlab::Error&) {
    }
  }
  return 0;
}
