#pragma once
// SpscRing<T>: a bounded single-producer single-consumer queue of preallocated slots. The
// producer never waits and never allocates: when the ring is full the new item is dropped and
// counted. The consumer takes items in order.
//
// Threading contract
// - Exactly one producer thread at a time calls BeginPush()/CommitPush() (or TryPush()).
// - Exactly one consumer thread at a time calls Front()/Pop() (or TryPop()).
// - Any thread: size(), dropped(), capacity().
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace urlab {

template <typename T>
class SpscRing {
 public:
  // `capacity` items, each a copy of `prototype` (e.g. vectors sized for the model).
  SpscRing(std::size_t capacity, const T& prototype)
      : slots_(capacity + 1, prototype), capacity_(capacity) {}

  std::size_t capacity() const { return capacity_; }
  // Items waiting (approximate while both sides run).
  std::size_t size() const {
    const std::size_t h = head_.load(std::memory_order_acquire);
    const std::size_t t = tail_.load(std::memory_order_acquire);
    return h >= t ? h - t : h + slots_.size() - t;
  }
  // Items the producer dropped because the ring was full.
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

  // Producer: the slot to fill next, or nullptr when full (the item is then counted as dropped).
  T* BeginPush() {
    const std::size_t h = head_.load(std::memory_order_relaxed);
    if (Next(h) == tail_.load(std::memory_order_acquire)) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return nullptr;
    }
    return &slots_[h];
  }
  // Producer: publishes the slot returned by the last successful BeginPush().
  void CommitPush() {
    head_.store(Next(head_.load(std::memory_order_relaxed)), std::memory_order_release);
  }
  // Producer: copies `item` in; false (and counted) when full.
  bool TryPush(const T& item) {
    T* slot = BeginPush();
    if (!slot) return false;
    *slot = item;
    CommitPush();
    return true;
  }

  // Consumer: the oldest item, nullptr when empty. Valid until Pop().
  T* Front() {
    const std::size_t t = tail_.load(std::memory_order_relaxed);
    return t == head_.load(std::memory_order_acquire) ? nullptr : &slots_[t];
  }
  // Consumer: releases the item returned by Front().
  void Pop() {
    tail_.store(Next(tail_.load(std::memory_order_relaxed)), std::memory_order_release);
  }
  // Consumer: swaps the oldest item into `*out` (no allocation when shapes match); false when
  // empty.
  bool TryPop(T* out) {
    T* item = Front();
    if (!item) return false;
    using std::swap;
    swap(*item, *out);
    Pop();
    return true;
  }

 private:
  std::size_t Next(std::size_t i) const { return i + 1 == slots_.size() ? 0 : i + 1; }

  std::vector<T> slots_;
  std::size_t capacity_;
  std::atomic<std::size_t> head_{0};  // next slot the producer fills
  std::atomic<std::size_t> tail_{0};  // next slot the consumer reads
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace urlab
