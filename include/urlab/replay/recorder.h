#pragma once
// The recorder: captures every physics step of a running engine into a recording file
// (recording.h), exactly and completely, without ever blocking the physics thread.
//
// It reads an every-step state ring (physics/state_frame.h), inactive while idle so that an idle
// recorder costs the physics thread nothing, and a command listener that captures the full state
// right after every command that made the state jump (reset, restore, set state, options). Full
// keyframes for seeking are captured by queued Inspect commands. A writer thread of its own
// encodes frames into chunks, compresses them and appends them to "PATH.part", flushed at least
// every `chunk_seconds` of wall time; Stop writes the end chunk, syncs and renames the file into
// place. A full ring drops frames: they are counted, logged and written as a gap.
//
// Threading contract
// - Main thread, engine not running: construction (subscribes), Attach. Destruction after the
//   engine stopped, or after Stop.
// - Any thread: Start, Stop, Save, Clear, status() (a small mutex serialises them; the physics
//   thread never takes it).
// - Physics thread: the command listener (pushes a captured state under a mutex held for a move,
//   only while recording) and the Inspect captures.
// - Writer thread: the ring, the encoder and the file.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "urlab/physics/engine.h"
#include "urlab/replay/recording.h"
#include "urlab/world/subsystem.h"

namespace urlab::replay {

// A request the recorder refuses; `code` is the step server's error code
// (recording_already_active, recording_not_active, path_not_writable, bad_value).
class RecorderError : public Error {
 public:
  RecorderError(std::string code, const std::string& message)
      : Error(message), code_(std::move(code)) {}
  const std::string& code() const { return code_; }

 private:
  std::string code_;
};

struct RecorderOptions {
  std::string path;  // the file to write ("" : a new file in the temporary folder)
  bool compress = true;
  int zstd_level = 3;
  bool sensordata = false;
  double keyframe_interval = 1.0;  // simulated seconds between full-state keyframes
  double chunk_seconds = 1.0;      // wall seconds between flushes: at most this is lost in a crash
  double max_duration = 0;         // simulated seconds to record, 0: unlimited
  std::uint64_t max_bytes = 0;     // file size to stop at, 0: unlimited
  // > 0: keep only the last ring_seconds simulated seconds, in memory; the file is written when
  // the recording stops (or by Save while it runs).
  double ring_seconds = 0;
};

// What a recording made.
struct RecorderStatus {
  bool active = false;
  std::string path;
  std::uint64_t frames = 0;      // steps recorded
  std::uint64_t chunks = 0;      // data chunks written (or held, in ring mode)
  std::uint64_t bytes = 0;       // file bytes so far (the header and the embedded model included)
  std::uint64_t data_bytes = 0;  // bytes of the data chunks (the steps) so far: per-step figures
  std::uint64_t raw_bytes = 0;   // uncompressed record bytes so far
  std::uint64_t dropped = 0;     // frames the ring lost
  std::uint64_t markers = 0;     // discontinuities recorded
  double duration = 0;           // simulated seconds recorded
  std::string stopped_because;   // "", "stopped", "max_duration", "max_bytes", "error: ..."
};

// What the recorder needs to know of the model, besides the engine.
struct RecorderSource {
  std::vector<std::string> articulations;  // names (joint tables get their short names)
  std::string mjcf;                        // the composed scene
  std::string scene;                       // the scene file, for the header
};

class Recorder {
 public:
  // Subscribes a ring of `ring_frames` frames (inactive) and a command listener on `engine`,
  // which must not be running; describes the model (MJB, extensions, hash; again at each Start,
  // with the physics options then in effect). Main thread.
  Recorder(physics::PhysicsEngine& engine, RecorderSource source, std::size_t ring_frames = 2048);
  // Stops a running recording (finishing its file) and removes the listener.
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Starts recording. Throws RecorderError: recording_already_active, path_not_writable,
  // bad_value (a negative or non-finite option).
  void Start(RecorderOptions options);
  // Finishes the recording: the last chunk, the end chunk, fsync, rename into place. Returns its
  // status. Throws RecorderError recording_not_active when idle.
  RecorderStatus Stop();
  // Writes the current recording (ring mode: the frames kept; else a copy of what is on disk so
  // far, finished) to `path` atomically, while it keeps recording. After Stop, copies the last
  // file. Throws RecorderError recording_not_active / path_not_writable.
  std::string Save(const std::string& path);
  // Forgets the last finished recording, deleting its file when it was a temporary one.
  void Clear();
  RecorderStatus status() const;
  bool active() const;
  // The header this recorder writes (model hash, tables, ...).
  const RecordingInfo& info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The recorder as a Manager subsystem: created in BeginPlay from the session (articulation names,
// composed MJCF), started at once when `autostart` has a path, stopped in EndPlay. Logs dropped
// frames at most once a second.
class RecorderSubsystem : public world::Subsystem {
 public:
  explicit RecorderSubsystem(std::optional<RecorderOptions> autostart = std::nullopt);
  ~RecorderSubsystem() override;
  std::string_view name() const override { return "recorder"; }
  void BeginPlay(world::Session& session) override;
  void Tick(world::Session& session, world::TickPhase phase) override;
  void EndPlay(world::Session& session) override;
  // The recorder while playing (nullptr before BeginPlay and after EndPlay). Any thread, under
  // the Recorder's contract.
  Recorder* recorder() { return recorder_.get(); }

 private:
  std::optional<RecorderOptions> autostart_;
  std::shared_ptr<world::Session> session_;  // outlives recorder_ (declared first)
  std::unique_ptr<Recorder> recorder_;
  std::uint64_t logged_dropped_ = 0;
  std::chrono::steady_clock::time_point last_log_{};
};

}  // namespace urlab::replay
