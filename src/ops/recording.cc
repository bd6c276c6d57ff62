// Recording and snapshots (urlab/ops/recording.h).
#include "urlab/ops/recording.h"

#include <functional>

#include "urlab/ops/error.h"
#include "urlab/physics/model.h"
#include "urlab/replay/recording.h"
#include "urlab/replay/snapshot.h"
#include "urlab/replay/tables.h"

namespace urlab::ops {

namespace {

using Reason = replay::RecordingError::Reason;

// Runs file work; its errors become OpErrors: the recorder's by their code, a recording's as
// bad_value (another model) or path_not_readable, anything else as `other` (rethrown when null).
template <typename Fn>
auto FileOp(Fn&& fn, const char* other = nullptr) {
  try {
    return fn();
  } catch (const OpError&) {
    throw;
  } catch (const replay::RecorderError& e) {
    Fail(e.code(), e.what());
  } catch (const replay::RecordingError& e) {
    Fail(e.reason() == Reason::kWrongModel ? "bad_value" : "path_not_readable", e.what());
  } catch (const std::exception& e) {
    if (!other) throw;
    Fail(other, e.what());
  }
}

}  // namespace

replay::Recorder& RequireRecorder(replay::RecorderSubsystem* recorder) {
  replay::Recorder* r = recorder ? recorder->recorder() : nullptr;
  if (!r) {
    Fail("not_ready",
         "this simulation has no recorder (run it with a recorder subsystem to record)");
  }
  return *r;
}

replay::Recorder& RequireIdleRecorder(replay::RecorderSubsystem* recorder) {
  replay::Recorder& r = RequireRecorder(recorder);
  if (r.active()) {
    Fail("recording_already_active", "a recording is already running (to " + r.status().path + ")");
  }
  return r;
}

std::string StartRecording(replay::RecorderSubsystem* recorder, const RecordingRequest& request) {
  replay::Recorder& r = RequireIdleRecorder(recorder);
  replay::RecorderOptions o;
  o.path = request.path;
  o.compress = request.compress;
  o.sensordata = request.sensordata;
  o.keyframe_interval = request.keyframe_interval;
  o.max_duration = request.max_duration;
  o.ring_seconds = request.ring_seconds;
  FileOp([&] { r.Start(std::move(o)); });
  return r.status().path;
}

replay::RecorderStatus StopRecording(replay::RecorderSubsystem* recorder) {
  replay::Recorder& r = RequireRecorder(recorder);
  return FileOp([&] { return r.Stop(); });
}

std::string SaveRecording(replay::RecorderSubsystem* recorder, const std::string& path) {
  replay::Recorder& r = RequireRecorder(recorder);
  return FileOp([&] { return r.Save(path); });
}

void ClearRecording(replay::RecorderSubsystem* recorder) {
  replay::Recorder& r = RequireRecorder(recorder);
  FileOp([&] { r.Clear(); });
}

replay::RecorderStatus RecordingStatus(replay::RecorderSubsystem* recorder) {
  return RequireRecorder(recorder).status();
}

double SaveSnapshot(world::Session& session, replay::RecorderSubsystem* recorder,
                    const std::string& path) {
  physics::PhysicsEngine& engine = session.engine();
  // The state and the model it belongs to, taken together (the options may change).
  physics::PhysicsState state;
  physics::Model model;
  engine.WithLockedData([&engine, &state, &model](mjModel* m, mjData* d) {
    state = physics::CaptureState(m, d);
    model = engine.owned_model().Copy();  // with its extensions
  });
  replay::RecordingInfo info;
  replay::Recorder* r = recorder ? recorder->recorder() : nullptr;
  if (r) {
    info = r->info();  // scene, MJCF and the articulations' name tables
  } else {
    std::vector<std::string> names;
    for (const world::Articulation& a : session.articulations()) names.push_back(a.name());
    info.tables = replay::ModelTables::Of(model.get(), names);
  }
  replay::DescribeModel(model, &info);  // the model as it is now
  FileOp([&] { replay::SaveSnapshot(path, info, state); }, "path_not_writable");
  return state.time;
}

Restored LoadSnapshot(world::Session& session, const std::string& path) {
  physics::PhysicsEngine& engine = session.engine();
  const physics::Model model = engine.CopyModel();
  physics::PhysicsState state =
      FileOp([&] { return replay::LoadSnapshot(path, model); }, "path_not_readable");
  Restored out;
  out.time = state.time;
  out.seq = RestoreState(session, std::move(state));
  return out;
}

physics::PhysicsState TakeState(world::Session& session) { return session.engine().Snapshot(); }

std::uint64_t RestoreState(world::Session& session, physics::PhysicsState state) {
  try {
    return session.engine().Restore(std::move(state));
  } catch (const Error& e) {
    Fail("bad_value", e.what());
  }
}

}  // namespace urlab::ops
