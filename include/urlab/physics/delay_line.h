#pragma once
// DelayLine: the one mechanism behind emulated latency (control, observation and camera delay).
// A value arrives once per tick (a physics step); it is released `delay` ticks later, plus a
// seeded jitter, and the line's output is the newest value released so far. Ticks are steps, so
// in lockstep a delay is exact in steps; what a delay in seconds or a distribution means is policy
// (physics/latency.h), which resolves a setting into a DelaySpec.
//
// Semantics, per tick t = 0, 1, 2, ... (Push(v) is tick t's arrival and returns tick t's output):
// - release(t) = max(release(t-1), t + delay + J(t)), J(t) uniform on the integers
//   -jitter..+jitter drawn from the line's own generator (splitmix64 of `seed`), and never below
//   t: values leave in the order they arrived (jitter never reorders; a value whose draw would
//   overtake an older one waits for it).
// - The output is the newest value with release <= t; before the first release it is the value
//   the owner primed the line with (Prime: the command in effect when the line started), else
//   the first value pushed (an observer sees the state the line started from).
// - Rate cap (`min_interval` > 1): the output changes only on ticks at least `min_interval`
//   ticks after its last change, taking the newest released value then; in between it holds.
// Restart() empties the line and restarts the generator from the seed (after a reset), so the
// same seed gives the same sequence of delays from every reset.
//
// Threading: none of its own; one thread at a time (the physics thread, under the step mutex).
#include <cstdint>
#include <utility>
#include <vector>

namespace urlab::physics {

// A delay resolved to ticks (physics steps).
struct DelaySpec {
  int delay = 0;         // ticks, >= 0
  int jitter = 0;        // +- ticks, uniform integer, >= 0
  int min_interval = 0;  // rate cap: ticks between output changes (0 or 1: every tick)
  std::uint64_t seed = 0;
  bool active() const { return delay > 0 || jitter > 0 || min_interval > 1; }
  bool operator==(const DelaySpec&) const = default;
};

// splitmix64: the generator of every emulated delay and random draw (small, fast, identical on
// every platform, unlike the distributions of <random>).
inline std::uint64_t SplitMix64(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
// A uniform double in [0, 1) from the generator's next 53 bits.
inline double UnitDouble(std::uint64_t* state) {
  return static_cast<double>(SplitMix64(state) >> 11) * 0x1.0p-53;
}
// A seed derived from `seed` and a stream number (articulation, channel), well mixed.
inline std::uint64_t DeriveSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t s = seed ^ (stream * 0xD1B54A32D192ED03ull);
  return SplitMix64(&s);
}

template <typename T>
class DelayLine {
 public:
  DelayLine() = default;
  explicit DelayLine(DelaySpec spec) { Configure(spec); }

  // Sets the spec and restarts the line.
  void Configure(DelaySpec spec) {
    spec_ = spec;
    if (spec_.delay < 0) spec_.delay = 0;
    if (spec_.jitter < 0) spec_.jitter = 0;
    if (spec_.min_interval < 0) spec_.min_interval = 0;
    // At most delay + jitter + 1 values wait for release at any tick (a release is at most
    // t + delay + jitter), plus up to min_interval held back by the rate cap; one more slot keeps
    // the ring from ever being full.
    const int held = spec_.min_interval > 1 ? spec_.min_interval : 1;
    slots_.resize(static_cast<std::size_t>(spec_.delay + spec_.jitter + held) + 2);
    Restart();
  }
  const DelaySpec& spec() const { return spec_; }
  bool active() const { return spec_.active(); }

  // Empties the line and restarts its generator and tick count (the slots keep their storage).
  void Restart() {
    rng_ = spec_.seed;
    head_ = tail_ = 0;
    tick_ = 0;
    last_release_ = -1;
    last_change_ = 0;
    has_output_ = false;
    last_jitter_ = 0;
  }

  // The output until the first release (after Configure or Restart).
  void Prime(const T& value) {
    output_ = value;
    has_output_ = true;
    last_change_ = 0;
  }

  // Tick t's arrival; returns tick t's output (valid until the next call).
  const T& Push(const T& value) {
    const std::int64_t t = tick_++;
    int j = 0;
    if (spec_.jitter > 0) {
      const auto span = static_cast<std::uint64_t>(2 * spec_.jitter + 1);
      j = static_cast<int>(
              static_cast<std::uint64_t>(UnitDouble(&rng_) * static_cast<double>(span))) -
          spec_.jitter;
    }
    last_jitter_ = j;
    std::int64_t release = t + spec_.delay + j;
    if (release < t) release = t;
    if (release < last_release_) release = last_release_;
    last_release_ = release;
    Slot& s = slots_[tail_];
    s.release = release;
    s.value = value;  // copy-assignment: no allocation once the slot holds a value of this size
    tail_ = Next(tail_);
    if (!has_output_) {  // the first value is the output until something is released
      output_ = value;
      has_output_ = true;
      last_change_ = t;
    }
    const bool may_change = spec_.min_interval <= 1 || t - last_change_ >= spec_.min_interval;
    if (may_change) {
      bool changed = false;
      while (head_ != tail_ && slots_[head_].release <= t) {
        std::swap(output_, slots_[head_].value);
        head_ = Next(head_);
        changed = true;
      }
      if (changed) last_change_ = t;
    }
    return output_;
  }

  // The current output without a tick (the first value before any Push: nullptr).
  const T* output() const { return has_output_ ? &output_ : nullptr; }
  // Ticks pushed since the last restart, and the jitter drawn for the last one.
  std::int64_t ticks() const { return tick_; }
  int last_jitter() const { return last_jitter_; }

 private:
  struct Slot {
    std::int64_t release = 0;
    T value{};
  };
  std::size_t Next(std::size_t i) const { return i + 1 == slots_.size() ? 0 : i + 1; }

  DelaySpec spec_;
  std::vector<Slot> slots_ = std::vector<Slot>(2);
  std::size_t head_ = 0, tail_ = 0;
  std::uint64_t rng_ = 0;
  std::int64_t tick_ = 0;
  std::int64_t last_release_ = -1;
  std::int64_t last_change_ = 0;
  bool has_output_ = false;
  int last_jitter_ = 0;
  T output_{};
};

}  // namespace urlab::physics
