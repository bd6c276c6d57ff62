#pragma once
// Clock: the time source of everything that paces or measures against wall time (the physics
// engine's pacing, its real-time factor and step rate, the rate limit of its divergence log). The
// real one is the steady clock; tests inject a ManualClock that moves only when told, so pacing
// and measurement are checked exactly instead of against a noisy machine's wall clock.
//
// Threading contract
// - Clock: now() and sleep_until() from any thread.
// - RealClock(): one immutable process-wide instance.
// - ManualClock: now(), sleep_until(), Advance(), Set(), sleepers() and WaitForSleeper() from any
//   thread (a small mutex; sleepers wait on a condition variable).
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <vector>

namespace urlab {

class Clock {
 public:
  using duration = std::chrono::steady_clock::duration;
  using time_point = std::chrono::steady_clock::time_point;
  virtual ~Clock() = default;
  virtual time_point now() const = 0;
  // Returns once now() >= deadline. May return earlier (callers re-check their own stop
  // condition and call again): a ManualClock returns after a short real wait so a thread asked to
  // stop is not held by time that never moves.
  virtual void sleep_until(time_point deadline) = 0;
};

// std::chrono::steady_clock. sleep_until sleeps to just before the deadline and yields for the
// rest (a sleep overshoots by about a scheduler tick).
Clock& RealClock();

// Time that moves only when Advance or Set says so. Starts at an arbitrary fixed point.
class ManualClock final : public Clock {
 public:
  time_point now() const override;
  // Blocks until Advance/Set reaches `deadline`, or at most `kMaxRealWait` of real time.
  void sleep_until(time_point deadline) override;

  void Advance(duration d);
  void Set(time_point t);
  // Threads blocked in sleep_until on a deadline still in the future.
  int sleepers() const;
  // Waits (real time, at most `timeout`) until at least `n` threads sleep on a future deadline:
  // the thread under test has done all it can at the current time. False on timeout.
  bool WaitForSleeper(int n = 1, std::chrono::milliseconds timeout = std::chrono::seconds(10));
  // Deadline calls to sleep_until so far (a test can count pacing waits).
  std::uint64_t sleep_calls() const;

  static constexpr auto kMaxRealWait = std::chrono::milliseconds(20);

 private:
  int SleepersLocked() const;

  mutable std::mutex mutex_;
  std::condition_variable cv_;          // time moved
  std::condition_variable sleeper_cv_;  // a sleeper arrived
  time_point now_ = time_point(std::chrono::hours(1));
  std::uint64_t sleep_calls_ = 0;
  std::vector<time_point> sleeping_;  // deadlines of the threads inside sleep_until
};

}  // namespace urlab
