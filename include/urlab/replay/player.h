#pragma once
// Playing recordings back.
//
// - LoadRecordedModel: the model a recording carries (its MJB), so playback needs no other file.
// - Resimulate: dynamic re-simulation without a physics thread: restore the first state, then
//   for every recorded step re-apply its inputs (ctrl, mocap poses, applied forces; the states
//   and options recorded at each jump) and advance one iteration of a physics::StepCore (the
//   engine's own stepping function, step_core.h), comparing time, qpos, qvel and act bit for
//   bit with the recording; the first divergent step is reported with the field and index.
// - Player: playback through a running engine's custom step handler, kinematic (each iteration
//   shows the recorded frame due on the recorded time axis: qpos, qvel, act, ctrl, mocap, time,
//   then mj_forward) or dynamic (each iteration re-simulates recorded steps on a StepCore of its
//   own over the recorded model, as Resimulate does, checks them and shows the re-simulated
//   state the same way).
//   Play, pause, speed, seek by time or step (from the chunk keyframe at or before it), loop.
//
// Threading contract
// - Resimulate, LoadRecordedModel: any thread; pure.
// - Player: construction and destruction on the main thread (it installs and removes the
//   engine's custom step handler); the controls (Play, Pause, SetSpeed, Seek*, SetLoop) and
//   status() from any thread (a small mutex the step handler takes once per iteration). The
//   handler runs on the physics thread.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "urlab/physics/engine.h"
#include "urlab/physics/model.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {

// The recording's compiled model, checked against the header's model hash.
// Throws RecordingError (kCorrupt) when they do not match or MuJoCo refuses the MJB.
physics::Model LoadRecordedModel(const RecordingReader& reader);

// Throws RecordingError (kWrongModel) naming both hashes when `m` is not the recorded model.
// Unless `compare_options`, the physics options are not compared (a recording carries those in
// effect at its start and every change, and re-applies them): `m` is hashed with the recorded
// options. `m` must not be stepping meanwhile (pass the engine's CopyModel()).
void CheckSameModel(const RecordingReader& reader, const physics::Model& m,
                    bool compare_options = false);

struct ResimReport {
  bool identical = false;  // every checked step matched bit for bit
  std::uint64_t steps_checked = 0;
  std::uint64_t frames = 0;  // frames in the recording
  bool diverged = false;
  std::uint64_t divergent_step = 0;   // the recorded step number
  std::uint64_t divergent_index = 0;  // 0-based frame index in the recording
  double divergent_time = 0;
  std::string field;    // "qpos", "qvel", "act" or "time"
  int index = -1;       // element of that field
  std::string element;  // the joint (or actuator) it belongs to, when known
  double recorded = 0, simulated = 0;
  std::string stopped;      // why it could not go on ("" when it reached the end)
  std::string str() const;  // one line for logs and the CLI
};

struct ResimOptions {
  bool stop_at_first_divergence = true;
  // Called every `progress_every` frames with (frames done, frames total).
  std::function<void(std::uint64_t, std::uint64_t)> progress;
  std::uint64_t progress_every = 10000;
};

// Re-simulates the whole recording on a copy of `m` (the recorded model when null). Throws
// RecordingError for a damaged chunk or another model.
ResimReport Resimulate(const RecordingReader& reader, const physics::Model* m = nullptr,
                       const ResimOptions& options = {});

// Landmarks of a recording for a timeline: where its keyframes are (seeks there are cheapest)
// and where its state jumped (resets, restores, state writes), by frame index.
struct TimelineMark {
  std::uint64_t frame = 0;  // index of the first frame after the mark
  std::uint64_t step = 0;
  double time = 0;
  std::string text;  // the jump's kind ("" for a keyframe)
};
struct TimelineMarks {
  std::uint64_t frames = 0;
  double first_time = 0, last_time = 0;
  std::vector<TimelineMark> keyframes;  // chunks that start with a full state
  std::vector<TimelineMark> jumps;      // markers (a reset is the usual one)
};
// Reads every chunk once. Throws RecordingError for a damaged chunk.
TimelineMarks ScanTimeline(const RecordingReader& reader);

enum class PlayMode { kKinematic, kResimulate };

struct PlayerOptions {
  PlayMode mode = PlayMode::kKinematic;
  double speed = 1.0;  // recorded seconds per simulated second of the engine's clock
  bool loop = false;
  bool start_paused = false;
};

struct PlayerStatus {
  bool playing = false;
  bool finished = false;
  double time = 0;           // recorded time of the frame shown
  std::uint64_t step = 0;    // its recorded step
  std::uint64_t frame = 0;   // its index
  std::uint64_t frames = 0;  // in the recording
  double speed = 1;
  bool loop = false;
  std::uint64_t loops = 0;
  ResimReport resim;  // dynamic mode: the checks so far
  std::string error;  // a chunk that could not be read
};

class Player {
 public:
  // Installs the custom step handler on `engine` (whose model must be the recorded one: throws
  // RecordingError kWrongModel otherwise). `reader` must outlive the Player.
  Player(physics::PhysicsEngine& engine, const RecordingReader& reader, PlayerOptions options);
  // Removes the handler.
  ~Player();
  Player(const Player&) = delete;
  Player& operator=(const Player&) = delete;

  void Play();
  void Pause();
  void SetSpeed(double speed);  // > 0, finite
  void SetLoop(bool loop);
  // The first frame at or after recorded time `t` / with step >= `step` / with this index
  // (0-based, clamped to the last frame). While paused the frame sought is shown and playback
  // stays paused (single steps: SeekFrame(status().frame + 1)).
  void SeekTime(double t);
  void SeekStep(std::uint64_t step);
  void SeekFrame(std::uint64_t index);
  PlayerStatus status() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace urlab::replay
