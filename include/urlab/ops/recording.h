#pragma once
// Recording and snapshots: start, stop, save, clear and the status of the recorder; the state
// saved to and loaded from a snapshot file; a state taken and restored in memory. One typed
// function per operation with one validation (ops::OpError with the wire code: not_ready without
// a recorder, the recorder's own codes such as recording_already_active, path_not_writable,
// path_not_readable, bad_value for a snapshot of another model), called alike by the step server
// (recording_*, snapshot_*) and the viewer's panel (Record, Stop recording, Snapshot, Restore).
// Paths are resolved by the caller (the step server: names under its files folder).
//
// Thread: any. File operations block the caller for their duration.
#include <cstdint>
#include <string>

#include "urlab/ops/error.h"
#include "urlab/physics/state.h"
#include "urlab/replay/recorder.h"
#include "urlab/world/session.h"

namespace urlab::ops {

// The recorder of `recorder` (a run's RecorderSubsystem, nullptr when it has none); not_ready
// when there is none.
replay::Recorder& RequireRecorder(replay::RecorderSubsystem* recorder);

// The recorder, not recording (recording_already_active while it is).
replay::Recorder& RequireIdleRecorder(replay::RecorderSubsystem* recorder);

struct RecordingRequest {
  std::string path;  // the file (written as path.part, renamed at the end)
  bool compress = true;
  bool sensordata = false;
  double keyframe_interval = 1.0;
  double max_duration = 0;
  double ring_seconds = 0;
};
// Starts recording; returns the file's path. recording_already_active while one runs.
std::string StartRecording(replay::RecorderSubsystem* recorder, const RecordingRequest& request);
replay::RecorderStatus StopRecording(replay::RecorderSubsystem* recorder);
// Writes what a ring-mode recording holds (or the finished file) to `path`; returns the path.
std::string SaveRecording(replay::RecorderSubsystem* recorder, const std::string& path);
void ClearRecording(replay::RecorderSubsystem* recorder);
replay::RecorderStatus RecordingStatus(replay::RecorderSubsystem* recorder);

// Saves the live state with the model it belongs to (the model as it is now, options included)
// to `path`; returns the state's time. The recorder, when there is one, names the scene and its
// articulations' tables. path_not_writable.
double SaveSnapshot(world::Session& session, replay::RecorderSubsystem* recorder,
                    const std::string& path);
// Restores the state of snapshot `path` (path_not_readable; bad_value for another model).
struct Restored {
  std::uint64_t seq = 0;  // the restore command
  double time = 0;        // the state's time
};
Restored LoadSnapshot(world::Session& session, const std::string& path);

// In memory: the live state, and a state put back (bad_value when it does not fit the model).
physics::PhysicsState TakeState(world::Session& session);
std::uint64_t RestoreState(world::Session& session, physics::PhysicsState state);

}  // namespace urlab::ops
