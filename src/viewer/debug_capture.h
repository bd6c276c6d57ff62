#pragma once
// DebugCapture: the debug drawing's data from the physics thread (the description's
// UMjDebugVisualizer::CaptureDebugData): a post-step callback copies the contacts, each with its
// force from mj_contactForce (ops::CollectContacts, the extractor get_contacts uses too), into the
// viewer's own buffer under the capture's own mutex. Only what a state frame does not carry is
// captured (body and geom poses come from the frame). The capture runs only when the viewer asked
// for one since the last, so with contact drawing off (or the viewer slower than the physics) the
// callback costs one atomic load per step.
//
// Threading contract
// - Physics thread (step mutex held): Capture, through the post-step callback.
// - Main thread: Request, Take, captures().
#include <mujoco/mujoco.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "urlab/ops/queries.h"

namespace urlab::viewer::internal {

// A contact as the one contact extractor (ops::CollectContacts) gives it, also to get_contacts.
using CapturedContact = ops::Contact;

class DebugCapture {
 public:
  // Physics thread: copies the contacts when a capture was requested.
  void Capture(const mjModel* m, const mjData* d);
  // Main thread: asks for a capture at the next iteration.
  void Request() { wanted_.store(true, std::memory_order_release); }
  // Main thread: swaps the newest capture into *out when there is one newer than the last Take.
  bool Take(std::vector<CapturedContact>* out);
  // Any thread: captures taken so far.
  std::uint64_t captures() const { return captures_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> wanted_{false};
  std::atomic<std::uint64_t> captures_{0};
  std::mutex mutex_;  // guards buffer_ and fresh_
  std::vector<CapturedContact> buffer_;
  bool fresh_ = false;
  ops::ContactList scratch_;  // physics thread
};

}  // namespace urlab::viewer::internal
