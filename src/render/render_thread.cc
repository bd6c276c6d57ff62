#include "render/render_thread.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

namespace urlab::render {

void PrepareRenderThread(int nice_increment) {
  if (nice_increment > 0) {
    const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
    setpriority(PRIO_PROCESS, tid, getpriority(PRIO_PROCESS, tid) + nice_increment);
  }
  if (!std::getenv("LP_NUM_THREADS")) {
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    setenv("LP_NUM_THREADS", std::to_string(std::max(1u, cores - 1)).c_str(), 0);
  }
}

}  // namespace urlab::render
