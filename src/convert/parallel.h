#pragma once
// ParallelFor: runs fn(0..n-1) on up to `threads` threads (the caller is one of them), each
// index exactly once; results go to slots the caller indexes, so the outcome never depends on
// scheduling. The first exception thrown by fn is rethrown on the caller once all have ended.
// Thread: the caller's; workers live only during the call. (Internal.)
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace urlab::convert::internal {

inline int HardwareThreads() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

template <typename Fn>
void ParallelFor(int n, int threads, Fn&& fn) {
  const int workers = std::clamp(threads, 1, std::max(n, 1));
  if (workers <= 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto run = [&] {
    for (int i = next++; i < n; i = next++) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) pool.emplace_back(run);
  run();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace urlab::convert::internal
