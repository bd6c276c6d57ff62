#include "core/worker_pool.h"

#include <pthread.h>

#include <string>

#include "core/spin_wait.h"
#include "urlab/core/error.h"

namespace urlab {

WorkerPool::WorkerPool(int threads) {
  if (threads < 1)
    throw Error("WorkerPool: threads must be at least 1 (got " + std::to_string(threads) + ")");
  workers_.reserve(static_cast<std::size_t>(threads - 1));
  for (int part = 1; part < threads; ++part) {
    workers_.emplace_back([this, part] {
      pthread_setname_np(pthread_self(), "urlab-worker");
      Work(part);
    });
  }
}

WorkerPool::~WorkerPool() {
  if (job_) {
    try {
      Finish();
    } catch (...) {  // nobody to tell: the job's owner is going away
    }
  }
  stop_.store(true, std::memory_order_release);
  generation_.fetch_add(1, std::memory_order_seq_cst);
  generation_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void WorkerPool::RunPart(int part) {
  try {
    (*job_)(part);
  } catch (...) {
    std::lock_guard<std::mutex> lock(error_mutex_);
    if (!error_) error_ = std::current_exception();
  }
}

void WorkerPool::Work(int part) {
  SpinWait spin;
  std::uint64_t seen = 0;
  while (true) {
    const auto moved = [&] { return generation_.load(std::memory_order_acquire) != seen; };
    if (!spin.Spin(kWorkerSpin, moved)) {
      sleeping_workers_.fetch_add(1, std::memory_order_seq_cst);
      generation_.wait(seen, std::memory_order_seq_cst);  // returns once it moved
      sleeping_workers_.fetch_sub(1, std::memory_order_relaxed);
    }
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_acquire)) return;
    RunPart(part);
    if (remaining_.fetch_sub(1, std::memory_order_seq_cst) == 1 &&
        owner_sleeping_.load(std::memory_order_seq_cst)) {
      remaining_.notify_one();
    }
  }
}

void WorkerPool::Run(const std::function<void(int part)>& fn) {
  Start(fn);
  Finish();
}

void WorkerPool::Start(const std::function<void(int part)>& fn) {
  if (job_) Finish();
  job_ = &fn;
  if (!workers_.empty()) {
    remaining_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_seq_cst);  // publishes job_ and remaining_
    if (sleeping_workers_.load(std::memory_order_seq_cst) > 0) generation_.notify_all();
  }
}

void WorkerPool::Finish() {
  if (!job_) return;
  RunPart(0);
  if (!workers_.empty()) {
    thread_local SpinWait spin;
    const auto done = [&] { return remaining_.load(std::memory_order_acquire) == 0; };
    if (!spin.Spin(kSpin, done)) {
      owner_sleeping_.store(true, std::memory_order_seq_cst);
      for (int r = remaining_.load(std::memory_order_seq_cst); r != 0;
           r = remaining_.load(std::memory_order_seq_cst)) {
        remaining_.wait(r, std::memory_order_seq_cst);
      }
      owner_sleeping_.store(false, std::memory_order_relaxed);
    }
  }
  job_ = nullptr;
  std::exception_ptr error;
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    std::swap(error, error_);
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace urlab
