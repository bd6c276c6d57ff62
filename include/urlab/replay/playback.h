#pragma once
// PlaybackSlot: the replay a running simulation plays, shared between whoever plays it (the step
// server's replay_start, `urlab replay --view`) and whoever shows it (the viewer's timeline),
// without either knowing the other: the app hands the same slot to both.
//
// Threading contract: any thread. The owner Sets a playback (and keeps its player and reader
// alive until it Sets another one or nullptr); users call With, which holds the slot's mutex for
// the call, so Set waits until no user touches the old playback. The physics thread never takes
// the slot's mutex.
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>

#include "urlab/replay/player.h"

namespace urlab::replay {

struct Playback {
  Player* player = nullptr;
  const RecordingReader* reader = nullptr;
  TimelineMarks marks;
  std::string label;  // what plays ("r1: run.urrec")
  std::string mode;   // "kinematic" or "resimulate"
};

class PlaybackSlot {
 public:
  // Owner: shows `playback` (nullptr: none).
  void Set(const Playback* playback) {
    std::lock_guard<std::mutex> lock(mutex_);
    current_ = playback;
    ++generation_;
  }
  // User: fn(const Playback* or nullptr), with the slot held.
  template <typename Fn>
  decltype(auto) With(Fn&& fn) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::forward<Fn>(fn)(current_);
  }
  // Changes with every Set (a user notices a new playback).
  std::uint64_t generation() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return generation_;
  }

 private:
  mutable std::mutex mutex_;
  const Playback* current_ = nullptr;
  std::uint64_t generation_ = 0;
};

}  // namespace urlab::replay
