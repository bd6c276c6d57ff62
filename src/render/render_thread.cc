#include "render/render_thread.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <string>
#include <thread>

namespace urlab::render {

void LimitSoftwareRasterThreads() {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  setenv("LP_NUM_THREADS", std::to_string(std::max(1u, cores - 1)).c_str(), /*overwrite=*/0);
}

bool LowerThreadPriority(int nice_increment) {
  if (nice_increment <= 0) return true;
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int now = getpriority(PRIO_PROCESS, tid);
  return errno == 0 && setpriority(PRIO_PROCESS, tid, now + nice_increment) == 0;
}

void PrepareRenderThread(int nice_increment) {
  LowerThreadPriority(nice_increment);
  LimitSoftwareRasterThreads();
}

}  // namespace urlab::render
