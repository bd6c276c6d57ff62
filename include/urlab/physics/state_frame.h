#pragma once
// State frames: what the physics thread publishes after each step (and after commands that
// change the state), for any number of readers that never touch live mjData.
//
// A reader subscribes before the physics thread starts, choosing one of two kinds:
// - StateSubscription (latest): the newest frame, through a triple buffer of its own, so readers
//   never see each other's progress and the physics thread never waits (viewer, network, cameras).
// - StateRing (every step): a bounded single-producer single-consumer ring of preallocated frames
//   with a drop counter (recorder). The physics thread never waits: a full ring drops and counts.
//
// Threading contract
// - Main thread, while the engine does not run: StatePublisher::Subscribe*, Unsubscribe.
// - Physics thread (step mutex held): StatePublisher::Publish.
// - One consumer thread per subscription: Latest() / TryPop() / Front() / Pop(); any thread:
//   the counters.
#include <mujoco/mujoco.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "urlab/core/spsc_ring.h"
#include "urlab/core/triple_buffer.h"

namespace urlab::physics {

// Why the state jumped right before a frame (bit flags; 0 for an ordinary step).
enum Discontinuity : std::uint32_t {
  kNoDiscontinuity = 0,
  kDiscontinuityReset = 1u << 0,     // full, keyframe or custom reset (also after divergence)
  kDiscontinuityRestore = 1u << 1,   // a PhysicsState was restored
  kDiscontinuitySetState = 1u << 2,  // qpos/qvel written by a command
  kDiscontinuityOptions = 1u << 3,   // physics options (or, by ReplaceModel, model values) changed
};

// Text for a set of Discontinuity flags ("reset|restore"), "" for none.
std::string DiscontinuityString(std::uint32_t flags);

// The command frames one step applied: one group per controlled articulation, laid out by the
// engine's command layout (PhysicsEngine::SetCommandLayout). The control layer fills them; the
// physics layer only carries them to the readers (a recorder keeps what a policy asked for beside
// what the robot did).
struct CommandGroupLayout {
  std::string name;            // the articulation
  std::vector<int> actuators;  // MuJoCo actuator ids, in the group's target order
  bool operator==(const CommandGroupLayout&) const = default;
};

struct AppliedCommands {
  std::vector<double> targets;       // concatenated over the groups, in layout order
  std::vector<double> kp, kv;        // gain overrides, same layout; NaN: the controller's own
  std::vector<std::uint64_t> seq;    // per group: the applied frame's publication number
  std::vector<std::uint8_t> source;  // per group: the control source it came from
  // Per group: 1 when the frame was raw (its targets were the actuators' controls as they are,
  // the controller did not run: control::CommandFrame::raw), else 0.
  std::vector<std::uint8_t> raw;
  // Sized for `layout`: zero targets, NaN gains, zero seq, source and raw.
  static AppliedCommands SizedFor(const std::vector<CommandGroupLayout>& layout);
  bool empty() const { return seq.empty(); }
};

// One published state. Arrays are sized for the model; a frame is only ever filled whole.
struct StateFrame {
  double time = 0;
  std::uint64_t step = 0;           // physics steps taken since the engine was constructed
  std::uint64_t frame = 0;          // frames published since construction (1 for the first)
  std::uint64_t command_seq = 0;    // newest command applied before this frame
  std::uint32_t discontinuity = 0;  // Discontinuity flags since the previous published frame
  std::uint64_t epoch = 0;  // discontinuities so far: a reader that skipped frames compares it
  bool paused = false;
  bool stepped = false;  // a physics step produced this frame (else commands or a pause did)
  int ncon = 0;
  std::vector<mjtNum> qpos, qvel, act, ctrl, qacc, sensordata;
  std::vector<mjtNum> actuator_force;         // per actuator
  std::vector<mjtNum> xpos, xquat;            // 3 / 4 per body
  std::vector<mjtNum> mocap_pos, mocap_quat;  // 3 / 4 per mocap body
  // The applied forces the step behind this frame used (one-shot forces included; when the
  // frame did not step, the current ones): with ctrl and the mocap poses, every input of
  // mj_step besides the state, so a recorder can re-simulate a run exactly.
  std::vector<mjtNum> qfrc_applied;  // nv
  std::vector<mjtNum> xfrc_applied;  // 6 per body
  // The command frames behind this frame's ctrl (empty without a command layout).
  AppliedCommands commands;

  // A frame with every array sized for `m` (zeros), and its commands for `layout`.
  static StateFrame SizedFor(const mjModel* m, const std::vector<CommandGroupLayout>& layout = {});
  // Copies everything from `d` except the bookkeeping fields (no allocation when sized);
  // `xfrc_applied`, when given, replaces d->xfrc_applied (6 * nbody values).
  void CopyFrom(const mjModel* m, const mjData* d, const mjtNum* xfrc_applied = nullptr);
};

// The bookkeeping of one publication.
struct FrameMeta {
  std::uint64_t step = 0;
  std::uint64_t frame = 0;
  std::uint64_t command_seq = 0;
  std::uint32_t discontinuity = 0;
  std::uint64_t epoch = 0;
  bool paused = false;
  bool stepped = false;
  const mjtNum* xfrc_applied = nullptr;       // the step's xfrc_applied when it differs from d's
  const AppliedCommands* commands = nullptr;  // the command frames applied last, when any
};

// Latest-frame subscription: one consumer thread reads the newest frame.
class StateSubscription {
 public:
  StateSubscription(std::string name, const mjModel* m,
                    const std::vector<CommandGroupLayout>& layout = {});
  const std::string& name() const { return name_; }
  // Made `observed`: frames pass through the publisher's observation delay.
  bool observed() const { return observed_; }
  // Consumer: the newest frame (stable until the next call), nullptr before the first.
  const StateFrame* Latest() { return buffer_.Latest(); }
  // Consumer: true when a frame newer than the last Latest() is waiting.
  bool has_new() const { return buffer_.has_new(); }
  // Any thread: frames published to this subscription.
  std::uint64_t published() const { return buffer_.published(); }

 private:
  friend class StatePublisher;
  std::string name_;
  TripleBuffer<StateFrame> buffer_;
  bool observed_ = false;
};

// Every-step subscription: one consumer thread takes frames in order.
class StateRing {
 public:
  StateRing(std::string name, const mjModel* m, std::size_t capacity,
            const std::vector<CommandGroupLayout>& layout = {});
  const std::string& name() const { return name_; }
  bool observed() const { return observed_; }
  // Consumer: swaps the oldest frame into *out (keep reusing the same frame); false when empty.
  bool TryPop(StateFrame* out) { return ring_.TryPop(out); }
  // Consumer: the oldest frame without copying, nullptr when empty; Pop() releases it.
  const StateFrame* Front() { return ring_.Front(); }
  void Pop() { ring_.Pop(); }
  // Any thread.
  std::size_t size() const { return ring_.size(); }
  std::size_t capacity() const { return ring_.capacity(); }
  std::uint64_t dropped() const { return ring_.dropped(); }
  // Any thread: an inactive ring is skipped by the publisher (nothing copied, nothing counted),
  // so a reader that only sometimes needs every step (an idle recorder) costs nothing meanwhile.
  // Rings start active.
  void SetActive(bool active) { active_.store(active, std::memory_order_release); }
  bool active() const { return active_.load(std::memory_order_acquire); }

 private:
  friend class StatePublisher;
  std::string name_;
  SpscRing<StateFrame> ring_;
  std::atomic<bool> active_{true};
  bool observed_ = false;
};

class ObservationDelay;

// The physics thread's side: fills every subscription.
class StatePublisher {
 public:
  explicit StatePublisher(const mjModel* m) : model_(m) {}
  // Main thread, before subscribing: frames of later subscriptions are sized for this layout.
  void SetCommandLayout(std::vector<CommandGroupLayout> layout) { layout_ = std::move(layout); }
  // Main thread, engine not running. `name` identifies the reader in logs. An `observed`
  // subscription gets the state as an observer sees it (SetObservationDelay); the others the
  // true state.
  std::shared_ptr<StateSubscription> SubscribeLatest(std::string name, bool observed = false);
  std::shared_ptr<StateRing> SubscribeEveryStep(std::string name, std::size_t capacity,
                                                bool observed = false);
  // Main thread, engine not running: the observation delay of observed subscriptions
  // (observation_delay.h); it runs on the publishing thread, under the step mutex.
  void SetObservationDelay(std::shared_ptr<ObservationDelay> delay) {
    observation_delay_ = std::move(delay);
  }
  ObservationDelay* observation_delay() const { return observation_delay_.get(); }
  // Main thread, engine not running: false when unknown.
  bool Unsubscribe(const void* subscription);
  int num_subscribers() const;
  // Physics thread: copies the state into every subscription.
  void Publish(const mjModel* m, const mjData* d, const FrameMeta& meta);
  // Step mutex held: gives one new latest-frame subscription the current state.
  static void PublishTo(StateSubscription& s, const mjModel* m, const mjData* d,
                        const FrameMeta& meta);

 private:
  const mjModel* model_;
  std::vector<CommandGroupLayout> layout_;
  std::vector<std::shared_ptr<StateSubscription>> latest_;
  std::vector<std::shared_ptr<StateRing>> rings_;
  std::shared_ptr<ObservationDelay> observation_delay_;
  StateFrame observed_;  // scratch: the observed frame of one publication
};

}  // namespace urlab::physics
