#pragma once
// Snapshots: one full physics state in a file of the recording format (recording.h) whose header
// says kind "snapshot" and carries the model (hash, tables, MJB), so loading one checks that it
// belongs to the model it is restored on.
//
// Thread: any (pure file I/O).
#include <mujoco/mujoco.h>

#include <string>

#include "urlab/physics/state.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {

// Writes `state` to `path` atomically: `model_info`'s header (model hash, tables, MJB...) with
// kind "snapshot", one data chunk holding StateRecord{0, state}. Throws Error naming the path.
void SaveSnapshot(const std::string& path, const RecordingInfo& model_info,
                  const physics::PhysicsState& state);

// The state a snapshot file holds. Throws RecordingError naming the file when it is not a
// readable snapshot (a recording, a damaged or truncated file), kWrongModel naming both hashes
// when it was taken on another model than `m`.
physics::PhysicsState LoadSnapshot(const std::string& path, const physics::Model& m);

}  // namespace urlab::replay
