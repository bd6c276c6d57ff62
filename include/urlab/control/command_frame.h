#pragma once
// Command frames: everything one message asks of one articulation's actuators (all targets, plus
// optional gains), published whole by a writer and read whole by the physics thread, so a
// 29-actuator command is never applied half old, half new.
//
// Threading contract (FrameChannel)
// - Any number of writer threads: Publish, Set, Patch, Get, Targets, last_seq. Writers serialise
//   among themselves on a small mutex held for one frame copy; the physics thread never takes it.
// - Physics thread only: Read (the newest complete frame, through a triple buffer).
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "urlab/core/triple_buffer.h"

namespace urlab::control {

// One articulation's command. Arrays are one entry per actuator, in the articulation's actuator
// order. A gain entry that is NaN leaves the controller's own gain in effect.
struct CommandFrame {
  std::vector<double> targets;
  std::vector<double> kp, kv;
  // The targets are the actuators' controls as they are (the step server's control_mode raw):
  // the controller does not run on this frame.
  bool raw = false;
  std::uint64_t seq = 0;  // publication number in its channel (0: the initial all-zero frame)
};

class FrameChannel {
 public:
  // A channel for `n` actuators whose first frame has all targets 0 and no gain overrides.
  explicit FrameChannel(std::size_t n);
  FrameChannel(const FrameChannel&) = delete;
  FrameChannel& operator=(const FrameChannel&) = delete;

  std::size_t size() const { return n_; }
  // Any thread: publishes a whole frame. `targets` must have size() values; `kp`/`kv` are empty
  // (gains unchanged) or size() values (NaN: that gain unchanged). Returns false on a size
  // mismatch (nothing published).
  bool Publish(std::span<const double> targets, std::span<const double> kp = {},
               std::span<const double> kv = {});
  // Any thread: publishes the last frame with some targets replaced ({index, value}); false
  // (nothing published) when an index is out of range.
  // `raw` given: the frame's raw flag from now on (CommandFrame::raw).
  bool Patch(std::span<const std::pair<int, double>> values, std::optional<bool> raw = {});
  // Any thread: one target (a Patch of one value).
  bool Set(int index, double value);
  // Any thread: publishes the last frame with its gain overrides patched (`kp`/`kv` empty or
  // size() values; NaN: that gain unchanged). False (nothing published) on a size mismatch.
  bool PatchGains(std::span<const double> kp, std::span<const double> kv);
  // Any thread: the gain overrides of the last published frame (NaN: the controller's own).
  std::pair<double, double> Gains(int index) const;
  // Any thread: a target / all targets of the last published frame.
  double Get(int index) const;
  std::vector<double> Targets() const;
  std::uint64_t last_seq() const;

  // Physics thread: the newest complete frame.
  const CommandFrame& Read() { return *buffer_.Latest(); }

 private:
  void PublishLocked();  // writer_mutex_ held: copies last_ out

  std::size_t n_;
  mutable std::mutex writer_mutex_;
  CommandFrame last_;  // the writers' copy of the newest frame
  TripleBuffer<CommandFrame> buffer_;
};

}  // namespace urlab::control
