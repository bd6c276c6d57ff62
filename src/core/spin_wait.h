#pragma once
// Bounded spin-waiting that gives up while the machine is oversubscribed. A thread that expects
// its event within microseconds (a lockstep request, a parked reply) spins instead of sleeping,
// since a wake-up from sleep costs more than the wait. But when there are more runnable threads
// than cores, spinning only delays the threads that would produce the event, and burns the
// spinner's scheduler credit so that it later waits a whole time slice for its core. A turn of
// the spin that took longer than kPreemptedTurn shows exactly that (the yield gave the core away):
// the wait ends and no spinning happens for kBackoff.
//
// Two paces: Spin yields the core on every turn (a waiter for another thread of this process
// that may need this very core); SpinTight turns with pause instructions and yields every
// kTightYieldTurns turns only, for a partner that answers within a microsecond or two (a
// shared-memory hand-over between processes): a yield is a system call, most of a microsecond on
// a virtual machine, and an event landing during it waits for its end.
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
  static constexpr unsigned kTightYieldTurns = 16;

  // Calls done() until it returns true (then true), for at most `limit`; false when the time
  // ran out or contention was seen (the caller then sleeps).
  template <class Done>
  bool Spin(Clock::duration limit, Done&& done) {
    return Turn(limit, done, 1);
  }
  // The same, yielding every kTightYieldTurns turns only.
  template <class Done>
  bool SpinTight(Clock::duration limit, Done&& done) {
    return Turn(limit, done, kTightYieldTurns);
  }

  // How often spinning was given up for contention (for tests and logs).
  unsigned long backoffs() const { return backoffs_; }

  // One pause of a spin loop (a hint to the core; no system call).
  static void CpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    asm volatile("yield" ::: "memory");
#endif
  }

 private:
  template <class Done>
  bool Turn(Clock::duration limit, Done& done, unsigned yield_every) {
    auto now = Clock::now();
    if (now < quiet_until_) return done();
    const auto until = now + limit;
    for (unsigned turn = 1;; ++turn) {
      if (done()) return true;
      if (turn % yield_every == 0) {
        std::this_thread::yield();
      } else {
        CpuRelax();
      }
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

  Clock::time_point quiet_until_{};
  unsigned long backoffs_ = 0;
};

}  // namespace urlab
