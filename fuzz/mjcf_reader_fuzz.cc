// libFuzzer target for the MJCF reader and writer: any input must either read (and then write
// and re-read to the same text) or fail with urlab::Error; never crash, hang or leak.
#include <cstddef>
#include <cstdint>
#include <string>

#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  urlab::mjcf::ReadOptions options;
  options.check_files = false;  // no disk access for assets
  try {
    urlab::document::Document doc = urlab::mjcf::ReadString(text, "/nonexistent/fuzz.xml", options);
    const std::string once = urlab::mjcf::WriteString(doc);
    urlab::document::Document again =
        urlab::mjcf::ReadString(once, "/nonexistent/fuzz.xml", options);
    if (urlab::mjcf::WriteString(again) != once) __builtin_trap();
  } catch (const urlab::Error&) {
  }
  return 0;
}
