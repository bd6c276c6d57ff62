#pragma once
// The wait policy of the shared-memory channel's clients (wire/shm_channel.h): how long a
// client waiting for its server spins before it sleeps. A wake-up from sleep costs tens of
// microseconds on a virtual machine whose CPU idles (the hypervisor has to wake it), a few when
// it is busy; a spin hand-over well under one. So a waiter spins about as long as its partner is
// expected to take, then sleeps, by these rules (SpinBudget):
//  - a short expected wait (up to kShortWait) is spun for three times over, at least kMinSpin:
//    the spin costs less than the wake-up it saves;
//  - a longer one, up to kMaxSpin, is spun for (expected x 5/4 + kSlack, at most kMaxSpin) when
//    a core is free for the spinner (SpareCore: no more runnable threads on the machine than
//    cores), and not at all otherwise: the waiter sleeps at once. A spinner without a core of
//    its own takes it from the threads it waits for (a driver gathering from two batched servers
//    on two cores; a batched server stepping on every core), just when their window starts. Even
//    kMinSpin of it cost a 64-environment step on 2 threads and 2 cores about 1.5% of its wall
//    time, and the server's wake-up of the client afterwards took 25 us instead of 5;
//  - a wait expected beyond kMaxSpin gets kMinSpin: the wake-up is small beside the wait, and
//    an idle peer must not burn a core.
// An expectation of zero or less (nothing learnt yet) gets kMinSpin. The spin loops themselves
// still end early when a turn shows the spinner lost its core.
//
// Threading: SpinBudget is a pure function; SpareCore reads /proc/loadavg (any thread).
#include <algorithm>
#include <chrono>
#include <string_view>

namespace urlab::wire {

struct ShmWait {
  using ns = std::chrono::nanoseconds;
  static constexpr ns kMinSpin = std::chrono::microseconds(30);
  static constexpr ns kShortWait = std::chrono::microseconds(100);
  static constexpr ns kSlack = std::chrono::microseconds(50);
  static constexpr ns kMaxSpin = std::chrono::milliseconds(3);
};

// How long to spin for a partner expected to take `expected`. `spare_core()` -> bool is asked
// only for a wait longer than kShortWait and up to kMaxSpin.
template <class SpareCoreFn>
std::chrono::nanoseconds SpinBudget(std::chrono::nanoseconds expected, SpareCoreFn&& spare_core) {
  using W = ShmWait;
  if (expected <= W::ns::zero() || expected > W::kMaxSpin) return W::kMinSpin;
  if (expected <= W::kShortWait) return std::max(W::kMinSpin, 3 * expected);
  if (!spare_core()) return W::ns::zero();
  return std::min(W::kMaxSpin, expected * 5 / 4 + W::kSlack);
}

// The steps a request runs, as ShmRoundTrips counts them: `n_steps` for a step or batch_step
// request, 0 for any other operation.
inline int RequestSteps(std::string_view op, int n_steps) {
  return op == "step" || op == "batch_step" ? n_steps : 0;
}

// What a client expects its next round trip to take (SpinBudget's `expected`): it learns the
// time per step from its step requests (a request of n steps: n times that) and the time of the
// other requests apart. Nothing learnt yet: zero. Threading: one per client.
class ShmRoundTrips {
 public:
  using ns = std::chrono::nanoseconds;
  // `steps`: the steps the request runs (0: a request that does not step).
  ns Expected(int steps) const { return steps > 0 ? per_step_ * steps : other_; }
  void Took(int steps, ns elapsed) {
    ns& learnt = steps > 0 ? per_step_ : other_;
    const ns sample = steps > 0 ? elapsed / steps : elapsed;
    learnt = learnt == ns::zero() ? sample : (learnt * 3 + sample) / 4;
  }

 private:
  ns per_step_{0}, other_{0};
};

// True when the machine has no more runnable threads (the caller among them) than online CPUs:
// a thread spinning now takes no core another runnable thread needs. False when it cannot tell.
bool SpareCore();

}  // namespace urlab::wire
