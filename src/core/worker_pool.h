#pragma once
// WorkerPool: a small set of persistent threads that run one job split into parts, in lockstep
// with the thread that hands it out (a batch of environments steps this way: no thread is
// created per step). Run(fn) calls fn(0) on the caller and fn(1) .. fn(K-1) on the K-1 workers,
// and returns once every part finished. Hand-off both ways spins briefly (SpinWait: not while
// the machine is oversubscribed) and otherwise waits on the atomic itself (a futex), with a
// system call to wake a waiter only when one sleeps.
//
// Threading contract
// - Construction, destruction, Run, Start and Finish: one owner (not reentrant; a part must not
//   call them). Threads may take turns as the owner when a lock of theirs orders their calls.
//   The owner blocks in Run and Finish until every part returned.
// - Parts run concurrently on distinct threads; what they share is theirs to keep apart (a batch
//   gives each part its own environments). Everything the owner wrote before Run is visible to
//   every part, and everything a part wrote is visible to the owner after Run.
// - An exception thrown by a part is rethrown by Run (the first one) after all parts finished.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace urlab {

class WorkerPool {
 public:
  // `threads` >= 1 parts per job; threads - 1 workers are started (1: the caller alone).
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  void Run(const std::function<void(int part)>& fn);
  // Run in two halves: Start hands parts 1 .. K-1 to the workers and returns at once; Finish
  // runs part 0 on the caller, waits for the others and rethrows. Between them the caller may
  // do other work (a batch steps the engine's own environment meanwhile); `fn` must live until
  // Finish returned. A second Start, or the destructor, first finishes a job started.
  void Start(const std::function<void(int part)>& fn);
  void Finish();
  bool started() const { return job_ != nullptr; }

  // How long the owner spins for the last part before sleeping (the parts end within one unit
  // of work of each other).
  static constexpr auto kSpin = std::chrono::microseconds(200);
  // How long a worker spins for the next job before sleeping: jobs that follow each other at
  // once (the iterations of a window) find it awake, and so does a batch server's next request
  // when its client answers within a few hundred microseconds (a Python vector env takes about
  // 100). A worker woken from sleep instead joined its job 50 to 400 us late on an idle virtual
  // machine, most of a 64-environment step's 1.2 ms on 2 threads. Its spin yields the core on
  // every turn, so a client computing meanwhile loses little; a client that takes longer finds
  // it asleep.
  static constexpr auto kWorkerSpin = std::chrono::microseconds(500);

 private:
  void Work(int part);
  void RunPart(int part);

  std::vector<std::thread> workers_;
  const std::function<void(int)>* job_ = nullptr;  // written by Run before the generation moves
  std::atomic<std::uint64_t> generation_{0};       // one per Run; workers wait for it to move
  std::atomic<int> remaining_{0};                  // parts of the current job not finished
  std::atomic<int> sleeping_workers_{0};
  std::atomic<bool> owner_sleeping_{false};
  std::atomic<bool> stop_{false};
  std::mutex error_mutex_;
  std::exception_ptr error_;
};

}  // namespace urlab
