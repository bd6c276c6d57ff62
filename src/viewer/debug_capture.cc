#include "viewer/debug_capture.h"

namespace urlab::viewer::internal {

void DebugCapture::Capture(const mjModel* m, const mjData* d) {
  if (!wanted_.exchange(false, std::memory_order_acq_rel)) return;
  ops::CollectContacts(m, d, {}, d->ncon, &scratch_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    buffer_.swap(scratch_.contacts);
    fresh_ = true;
  }
  captures_.fetch_add(1, std::memory_order_relaxed);
}

bool DebugCapture::Take(std::vector<CapturedContact>* out) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!fresh_) return false;
  out->swap(buffer_);
  fresh_ = false;
  return true;
}

}  // namespace urlab::viewer::internal
