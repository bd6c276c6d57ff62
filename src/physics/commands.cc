#include "urlab/physics/commands.h"

namespace urlab::physics {

std::uint64_t CommandQueue::Push(Command command) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::uint64_t seq = next_seq_++;
  queue_.push_back({seq, std::move(command)});
  has_pending_.store(true, std::memory_order_release);
  return seq;
}

CommandResult CommandQueue::Wait(std::uint64_t seq, Clock::duration timeout) {
  // Announce the waiter before looking at finished_ (both sequentially consistent), so Finish
  // either sees the waiter and notifies under the mutex, or the waiter sees the command done.
  waiters_.fetch_add(1);
  std::unique_lock<std::mutex> lock(mutex_);
  CommandResult result{CommandStatus::kApplied, {}};
  if (seq == 0 || seq >= next_seq_) {
    result.status = CommandStatus::kUnknown;
  } else if (!cv_.wait_for(lock, timeout, [&] { return finished_.load() >= seq; })) {
    result.status = CommandStatus::kTimeout;
  } else if (auto it = failures_.find(seq); it != failures_.end()) {
    result = {CommandStatus::kFailed, it->second};
  }
  lock.unlock();
  waiters_.fetch_sub(1);
  return result;
}

void CommandQueue::TakeAll(std::deque<Entry>* out) {
  if (!has_pending_.load(std::memory_order_acquire)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (out->empty()) {
    out->swap(queue_);
  } else {
    for (Entry& e : queue_) out->push_back(std::move(e));
    queue_.clear();
  }
  has_pending_.store(false, std::memory_order_release);
}

void CommandQueue::Finish(std::uint64_t seq, std::string error) {
  if (!error.empty()) {
    std::lock_guard<std::mutex> lock(mutex_);
    failures_.emplace(seq, std::move(error));
    while (failures_.size() > kRememberedFailures) failures_.erase(failures_.begin());
  }
  finished_.store(seq);
  if (waiters_.load() > 0) {
    std::lock_guard<std::mutex> lock(mutex_);  // a waiter between its check and its wait
    cv_.notify_all();
  }
}

}  // namespace urlab::physics
