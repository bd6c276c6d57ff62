#include "urlab/core/clock.h"

#include <algorithm>
#include <thread>

namespace urlab {

namespace {

// Below this much remaining wait the real clock yields instead of sleeping (sleep overshoots).
constexpr auto kSpinMargin = std::chrono::microseconds(200);

class SteadyClock final : public Clock {
 public:
  time_point now() const override { return std::chrono::steady_clock::now(); }
  void sleep_until(time_point deadline) override {
    for (auto t = now(); t < deadline; t = now()) {
      const auto remaining = deadline - t;
      if (remaining > kSpinMargin) {
        std::this_thread::sleep_for(remaining - kSpinMargin);
      } else {
        std::this_thread::yield();
      }
    }
  }
};

}  // namespace

Clock& RealClock() {
  static SteadyClock clock;
  return clock;
}

Clock::time_point ManualClock::now() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return now_;
}

void ManualClock::sleep_until(time_point deadline) {
  std::unique_lock<std::mutex> lock(mutex_);
  ++sleep_calls_;
  if (now_ >= deadline) return;
  sleeping_.push_back(deadline);
  sleeper_cv_.notify_all();
  cv_.wait_for(lock, kMaxRealWait, [&] { return now_ >= deadline; });
  sleeping_.erase(std::find(sleeping_.begin(), sleeping_.end(), deadline));
}

void ManualClock::Advance(duration d) {
  std::lock_guard<std::mutex> lock(mutex_);
  now_ += d;
  cv_.notify_all();
}

void ManualClock::Set(time_point t) {
  std::lock_guard<std::mutex> lock(mutex_);
  now_ = t;
  cv_.notify_all();
}

int ManualClock::SleepersLocked() const {
  return static_cast<int>(
      std::count_if(sleeping_.begin(), sleeping_.end(), [&](time_point d) { return d > now_; }));
}

int ManualClock::sleepers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return SleepersLocked();
}

bool ManualClock::WaitForSleeper(int n, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  return sleeper_cv_.wait_for(lock, timeout, [&] { return SleepersLocked() >= n; });
}

std::uint64_t ManualClock::sleep_calls() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sleep_calls_;
}

}  // namespace urlab
