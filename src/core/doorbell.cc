#include "urlab/core/doorbell.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

#include "urlab/core/error.h"

namespace urlab {

Doorbell::Doorbell() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw Error(std::string("cannot create an eventfd: ") + std::strerror(errno));
}

Doorbell::~Doorbell() {
  if (fd_ >= 0) close(fd_);
}

void Doorbell::Ring() {
  if (!armed_.exchange(false, std::memory_order_seq_cst)) return;
  const std::uint64_t one = 1;
  // EAGAIN (the counter is saturated) still leaves the fd readable: nothing to do.
  [[maybe_unused]] const ssize_t n = write(fd_, &one, sizeof(one));
}

void Doorbell::Clear() {
  armed_.store(false, std::memory_order_seq_cst);
  std::uint64_t count = 0;
  [[maybe_unused]] const ssize_t n = read(fd_, &count, sizeof(count));
}

}  // namespace urlab
