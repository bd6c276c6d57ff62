#include "wire/shm_wait.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdlib>

namespace urlab::wire {

namespace {

// The runnable threads of the whole machine now (the 4th field of /proc/loadavg, "R/T"), or -1.
int RunnableThreads() {
  static const int fd = open("/proc/loadavg", O_RDONLY | O_CLOEXEC);  // kept: one pread a call
  if (fd < 0) return -1;
  char text[128];
  const ssize_t n = pread(fd, text, sizeof(text) - 1, 0);
  if (n <= 0) return -1;
  text[n] = '\0';
  // "0.52 0.58 0.59 2/150 12345": the number after the third space.
  const char* p = text;
  for (int spaces = 0; spaces < 3 && *p != '\0'; ++p) spaces += *p == ' ';
  char* end = nullptr;
  const long r = std::strtol(p, &end, 10);
  return end != p && *end == '/' ? static_cast<int>(r) : -1;
}

}  // namespace

bool SpareCore() {
  static const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  const int runnable = RunnableThreads();
  return runnable > 0 && cores > 0 && runnable <= cores;
}

}  // namespace urlab::wire
