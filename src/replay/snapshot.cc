#include "urlab/replay/snapshot.h"

#include <variant>
#include <vector>

#include "urlab/replay/player.h"

namespace urlab::replay {

using Reason = RecordingError::Reason;

void SaveSnapshot(const std::string& path, const RecordingInfo& model_info,
                  const physics::PhysicsState& state) {
  RecordingInfo info = model_info;
  info.kind = "snapshot";
  WriteRecording(path, info, {{Record{StateRecord{0, state}}}});
}

physics::PhysicsState LoadSnapshot(const std::string& path, const physics::Model& m) {
  const RecordingReader reader = RecordingReader::Open(path);
  if (reader.info().kind != "snapshot") {
    throw RecordingError(Reason::kNotARecording, path,
                         "not a snapshot (a file of kind '" + reader.info().kind + "')");
  }
  CheckSameModel(reader, m, /*compare_options=*/true);  // a state restores with its options
  for (std::size_t i = 0; i < reader.chunks().size(); ++i) {
    for (Record& r : reader.ReadChunk(i)) {
      if (auto* s = std::get_if<StateRecord>(&r)) return std::move(s->state);
    }
  }
  throw RecordingError(Reason::kCorrupt, path, "the snapshot holds no state");
}

}  // namespace urlab::replay
