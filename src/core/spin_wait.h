#pragma once
// Bounded spin-waiting that gives up while the machine is oversubscribed. A thread that expects
// its event within microseconds (a lockstep request, a parked reply) spins instead of sleeping,
// since a wake-up from sleep costs more than the wait. But when there are more runnable threads
// than cores, spinning only delays the threads that would produce the event, and burns the
// spinner's scheduler credit so that it later waits a whole time slice for its core. A turn of
// the spin that took longer than kPreemptedTurn shows exactly that (the yield gave the core away):
// the wait ends and no spinning happens for kBackoff.
//
// Threading: one object per waiting thread (not shared).
#include <chrono>
#include <thread>

namespace urlab {

class SpinWait {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr auto kPreemptedTurn = std::chrono::microseconds(500);
  static constexpr auto kBackoff = std::chrono::milliseconds(20);

  // Calls done() until it returns true (then true), for at most `limit`; false when the time
  // ran out or contention was seen (the caller then sleeps).
  template <class Done>
  bool Spin(Clock::duration limit, Done&& done) {
    auto now = Clock::now();
    if (now < quiet_until_) return done();
    const auto until = now + limit;
    while (true) {
      if (done()) return true;
      std::this_thread::yield();
      const auto before = now;
      now = Clock::now();
      if (now - before > kPreemptedTurn) {
        quiet_until_ = now + kBackoff;
        ++backoffs_;
        return done();
      }
      if (now >= until) return false;
    }
  }

  // How often spinning was given up for contention (for tests and logs).
  unsigned long backoffs() const { return backoffs_; }

 private:
  Clock::time_point quiet_until_{};
  unsigned long backoffs_ = 0;
};

}  // namespace urlab
