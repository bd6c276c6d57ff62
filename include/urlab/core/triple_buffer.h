#pragma once
// TripleBuffer<T>: hands the newest value from one producer thread to one consumer thread without
// either side ever waiting for the other. The producer fills Back() and calls Publish(); the
// consumer calls Latest() and may use the returned value until its next call to Latest().
//
// Threading contract
// - Exactly one producer thread at a time calls Back() and Publish() (writers that share a buffer
//   serialise among themselves, e.g. with their own mutex).
// - Exactly one consumer thread at a time calls Latest() and has_new().
#include <array>
#include <atomic>
#include <cstdint>

namespace urlab {

template <typename T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  // Every slot starts as a copy of `initial` (e.g. vectors sized for the model).
  explicit TripleBuffer(const T& initial) : slots_{initial, initial, initial} {}

  // Producer: the slot to fill; its contents are whatever was published two publications ago.
  T& Back() { return slots_[back_]; }
  // Producer: makes Back() the newest value and hands a free slot back.
  void Publish() {
    back_ = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) & kIndex;
    published_.fetch_add(1, std::memory_order_release);
  }

  // Consumer: true when a value newer than the last Latest() result is waiting.
  bool has_new() const { return (middle_.load(std::memory_order_acquire) & kFresh) != 0; }
  // Consumer: the newest published value (stable until the next call), nullptr before the first
  // publication.
  const T* Latest() {
    if (middle_.load(std::memory_order_acquire) & kFresh) {
      front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
      has_front_ = true;
    }
    return has_front_ ? &slots_[front_] : nullptr;
  }
  // Any thread: publications so far.
  std::uint64_t published() const { return published_.load(std::memory_order_acquire); }

  // Any thread, only while neither side runs: every slot (e.g. to resize them together).
  std::array<T, 3>& slots() { return slots_; }

 private:
  static constexpr std::uint32_t kFresh = 4;
  static constexpr std::uint32_t kIndex = 3;
  std::array<T, 3> slots_{};
  std::atomic<std::uint32_t> middle_{1};
  std::atomic<std::uint64_t> published_{0};
  std::uint32_t back_ = 0;   // producer-owned
  std::uint32_t front_ = 2;  // consumer-owned
  bool has_front_ = false;   // consumer-owned
};

}  // namespace urlab
