#include "viewer/debug_capture.h"

#include <algorithm>

namespace urlab::viewer::internal {

void DebugCapture::Capture(const mjModel* m, const mjData* d) {
  if (!wanted_.exchange(false, std::memory_order_acq_rel)) return;
  scratch_.resize(static_cast<std::size_t>(d->ncon));
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    CapturedContact& out = scratch_[static_cast<std::size_t>(i)];
    std::copy_n(c.pos, 3, out.pos);
    std::copy_n(c.frame, 9, out.frame);
    mj_contactForce(m, d, i, out.force);
    out.dist = c.dist;
    out.geom1 = c.geom1;
    out.geom2 = c.geom2;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    buffer_.swap(scratch_);
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
