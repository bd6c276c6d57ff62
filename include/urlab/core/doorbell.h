#pragma once
// Doorbell: wakes a consumer thread that sleeps in poll(2) (or zmq_poll) when a producer has
// something for it, without a system call on the producer's side while the consumer is awake.
// Backed by a Linux eventfd, so the consumer can wait for it together with sockets.
//
// Threading contract
// - Any number of producer threads call Ring().
// - One consumer thread calls Arm(), polls fd() for POLLIN, then Clear().
// - The consumer arms before its last check for work and sleeps only if that check finds none:
//   a Ring() after Arm() always makes fd() readable, so no wake-up is lost.
#include <atomic>

namespace urlab {

class Doorbell {
 public:
  Doorbell();  // throws urlab::Error when the kernel refuses an eventfd
  ~Doorbell();
  Doorbell(const Doorbell&) = delete;
  Doorbell& operator=(const Doorbell&) = delete;

  // Readable while rung and not cleared.
  int fd() const { return fd_; }
  // Producer: wakes the consumer if it is armed (a write(2) only then).
  void Ring();
  // Consumer: about to check for work and sleep.
  void Arm() { armed_.store(true, std::memory_order_seq_cst); }
  // Consumer: awake again; disarms and drains the eventfd.
  void Clear();

 private:
  int fd_ = -1;
  std::atomic<bool> armed_{false};
};

}  // namespace urlab
