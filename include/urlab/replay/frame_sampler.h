#pragma once
// FrameSampler: a recording's state at evenly spaced points of its time axis, for frame-exact
// video (`urlab render`): frame k of a video at `fps` shows the state at position k / fps.
//
// The axis: position 0 is the recording's start state (its first keyframe, or its first frame
// when it has none); each recorded step advances the position by its time difference, and a
// step whose time does not advance (a jump, such as a reset back to t = 0) by one recorded
// timestep, as the Player counts it. The state at a position is the last recorded state at or
// before it (1 ns of slack against rounding in the summed times).
//
// Thread: one thread at a time.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "urlab/physics/state_frame.h"
#include "urlab/replay/recording.h"

namespace urlab::replay {

class FrameSampler {
 public:
  // Scans the recording once for its length. `reader` must outlive the sampler. Throws
  // RecordingError for a damaged chunk.
  explicit FrameSampler(const RecordingReader& reader);

  // Positions the recording covers: the last recorded step's position (0 for a single state).
  double duration() const { return duration_; }
  // Frames of a video at `fps` covering the recording: those at positions k / fps below
  // duration(), at least one (a recording of D seconds at F frames/s gives ceil(D F) frames).
  std::uint64_t FrameCount(double fps) const;

  // The state at `position` (positions must not decrease from call to call): time, step, qpos,
  // qvel, act, ctrl, mocap poses and applied forces of the last recorded state at or before it.
  // The frame stays valid until the next call. Throws RecordingError for a damaged chunk.
  const physics::StateFrame& At(double position);

 private:
  // Where the walk through the records is.
  struct Cursor {
    std::size_t chunk = 0;
    std::vector<Record> records;
    std::size_t next = 0;
    bool loaded = false;
    bool have_start = false;  // a keyframe came before the first step: position 0
    physics::PhysicsState start;
    bool have_axis = false;  // a step has been placed on the axis
    double last_time = 0;    // recorded time of the last step placed
    double last_pos = 0;     // and its position
    bool jumped = false;     // a marker since then
    bool have_pending = false;
    Frame pending;  // the next step, at position last_pos
  };
  // Places the next recorded step on the axis (cursor.pending); false at the end.
  bool Next(Cursor& c) const;
  void Take(const Frame& f);
  void TakeState(const physics::PhysicsState& s);

  const RecordingReader& reader_;
  double dt_ = 0;
  double duration_ = 0;
  Cursor cursor_;
  bool started_ = false;
  physics::StateFrame frame_;
};

}  // namespace urlab::replay
