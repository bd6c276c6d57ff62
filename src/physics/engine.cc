#include "urlab/physics/engine.h"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "core/spin_wait.h"
#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

using SteadyClock = std::chrono::steady_clock;

// Longest single wait, so that Stop() is honoured promptly even with long intervals.
constexpr auto kMaxSleep = std::chrono::milliseconds(20);
// How long a paused loop waits for the next lockstep request without sleeping.
constexpr auto kLockstepSpin = std::chrono::microseconds(500);
// Running as fast as possible, the doorbells are rung at most this often (real time: what a
// wake-up costs): a consumer woken for every 30 µs step costs the loop more than it gains.
constexpr auto kRingCoalesce = std::chrono::microseconds(50);

std::string Describe(const EngineEvent& e) {
  std::string s = e.message;
  if (e.joint_id >= 0) {
    s += " (joint " + (e.joint_name.empty() ? "#" + std::to_string(e.joint_id) : e.joint_name);
    if (!e.articulation.empty()) s += ", articulation " + e.articulation;
    s += ")";
  }
  return s;
}

// The engine whose iteration the current thread is running (set while callbacks may run).
thread_local const PhysicsEngine* tls_iterating = nullptr;

struct IteratingScope {
  explicit IteratingScope(const PhysicsEngine* e) : saved(tls_iterating) { tls_iterating = e; }
  ~IteratingScope() { tls_iterating = saved; }
  const PhysicsEngine* saved;
};

StepCore::Options CoreOptions(const PhysicsEngine::Options& o) {
  StepCore::Options c;
  c.reset_on_divergence = o.reset_on_divergence;
  c.log_command_failures = o.log_events;
  return c;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Construction and lifecycle

PhysicsEngine::PhysicsEngine(Model model) : PhysicsEngine(std::move(model), Options{}) {}

PhysicsEngine::PhysicsEngine(Model model, Options options)
    : core_(model ? std::move(model) : throw Error("PhysicsEngine needs a compiled model"),
            CoreOptions(options)),
      clock_(options.clock ? options.clock : &RealClock()) {
  SetSpeedPercent(options.speed_percent);
  SetTargetInterval(options.target_interval);
  as_fast_.store(options.as_fast_as_possible);
  resync_threshold_ = options.resync_threshold;
  log_events_ = options.log_events;
  measure_window_ = options.measure_window > 0 ? options.measure_window : 0.25;
  core_.SetEventSink([this](EngineEvent e) { OnEvent(std::move(e)); });
}

PhysicsEngine::~PhysicsEngine() { Stop(); }

void PhysicsEngine::Start() {
  ThrowIfOnPhysicsThread("Start");
  if (running_.load()) throw Error("PhysicsEngine::Start: the physics thread is already running");
  stop_.store(false);
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] {
    pthread_setname_np(pthread_self(), "urlab-physics");  // for top -H, perf, gdb
    Loop();
  });
}

void PhysicsEngine::Stop() {
  if (!thread_.joinable()) return;
  ThrowIfOnPhysicsThread("Stop");
  stop_.store(true, std::memory_order_release);
  wake_cv_.notify_all();
  thread_.join();
  running_.store(false, std::memory_order_release);
  // Commands queued while the thread was winding down are applied now.
  std::lock_guard<std::mutex> lock(step_mutex_);
  IteratingScope scope(this);
  AfterPublishLocked(core_.ApplyPending(), false);
  if (unrung_) RingDoorbellsLocked();
}

void PhysicsEngine::WithLockedData(const std::function<void(mjModel*, mjData*)>& fn) {
  ThrowIfOnPhysicsThread("WithLockedData");
  std::lock_guard<std::mutex> lock(step_mutex_);
  fn(core_.mutable_model(), core_.data());
}

Model PhysicsEngine::CopyModel() {
  ThrowIfOnPhysicsThread("CopyModel");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.owned_model().Copy();
}

void PhysicsEngine::ThrowIfOnPhysicsThread(const char* what) const {
  if (tls_iterating == this) {
    throw Error(std::string("PhysicsEngine::") + what +
                " called from inside a step callback (would deadlock)");
  }
}

// ---------------------------------------------------------------------------------------------
// Hooks (registered in the core under the step mutex)

PhysicsEngine::CallbackId PhysicsEngine::AddPreStepCallback(StepCallback fn) {
  ThrowIfOnPhysicsThread("AddPreStepCallback");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.AddHook(StepCore::HookKind::kPreStep, std::move(fn));
}
PhysicsEngine::CallbackId PhysicsEngine::AddPostStepCallback(StepCallback fn) {
  ThrowIfOnPhysicsThread("AddPostStepCallback");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.AddHook(StepCore::HookKind::kPostStep, std::move(fn));
}
PhysicsEngine::CallbackId PhysicsEngine::AddOnPostStep(StepCallback fn) {
  ThrowIfOnPhysicsThread("AddOnPostStep");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.AddHook(StepCore::HookKind::kOnPostStep, std::move(fn));
}

bool PhysicsEngine::RemoveCallback(CallbackId id) {
  ThrowIfOnPhysicsThread("RemoveCallback");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.RemoveCallback(id);
}

void PhysicsEngine::SetApplyControlsHook(StepCallback fn) {
  ThrowIfOnPhysicsThread("SetApplyControlsHook");
  std::lock_guard<std::mutex> lock(step_mutex_);
  core_.SetApplyControlsHook(std::move(fn));
}

void PhysicsEngine::SetCommandLayout(std::vector<CommandGroupLayout> layout) {
  ThrowIfOnPhysicsThread("SetCommandLayout");
  std::lock_guard<std::mutex> lock(step_mutex_);
  core_.SetCommandLayout(std::move(layout));
}

void PhysicsEngine::SetCustomStepHandler(StepCallback fn) {
  ThrowIfOnPhysicsThread("SetCustomStepHandler");
  std::lock_guard<std::mutex> lock(step_mutex_);
  core_.SetCustomStepHandler(std::move(fn));
}

void PhysicsEngine::SetArticulationResolver(ArticulationResolver fn) {
  ThrowIfOnPhysicsThread("SetArticulationResolver");
  std::lock_guard<std::mutex> lock(step_mutex_);
  core_.SetArticulationResolver(std::move(fn));
}

PhysicsEngine::CallbackId PhysicsEngine::AddCommandListener(CommandListener fn) {
  ThrowIfOnPhysicsThread("AddCommandListener");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.AddCommandListener(std::move(fn));
}

// ---------------------------------------------------------------------------------------------
// State readers

std::shared_ptr<StateSubscription> PhysicsEngine::SubscribeState(std::string name, bool observed) {
  ThrowIfOnPhysicsThread("SubscribeState");
  if (running()) throw Error("SubscribeState('" + name + "'): subscribe before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  auto s = core_.publisher().SubscribeLatest(std::move(name), observed);
  // The current state, so a reader has a frame before the first step (others get nothing new).
  StatePublisher::PublishTo(*s, core_.model(), core_.data(), core_.CurrentMeta());
  return s;
}

std::shared_ptr<StateRing> PhysicsEngine::SubscribeEveryStep(std::string name, std::size_t capacity,
                                                             bool observed) {
  ThrowIfOnPhysicsThread("SubscribeEveryStep");
  if (running()) throw Error("SubscribeEveryStep('" + name + "'): subscribe before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.publisher().SubscribeEveryStep(std::move(name), capacity, observed);
}

void PhysicsEngine::SetObservationDelay(std::shared_ptr<ObservationDelay> delay) {
  ThrowIfOnPhysicsThread("SetObservationDelay");
  if (running()) throw Error("SetObservationDelay: set it before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  core_.publisher().SetObservationDelay(std::move(delay));
}

void PhysicsEngine::AddDoorbell(std::shared_ptr<Doorbell> doorbell) {
  ThrowIfOnPhysicsThread("AddDoorbell");
  if (running()) throw Error("AddDoorbell: add it before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  doorbells_.push_back(std::move(doorbell));
}

bool PhysicsEngine::Unsubscribe(const void* subscription) {
  ThrowIfOnPhysicsThread("Unsubscribe");
  if (running()) throw Error("Unsubscribe: stop the engine first");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return core_.publisher().Unsubscribe(subscription);
}

// ---------------------------------------------------------------------------------------------
// Commands

std::uint64_t PhysicsEngine::Submit(Command command) {
  core_.Validate(command);
  const std::uint64_t seq = core_.commands().Push(std::move(command));
  if (!running() && tls_iterating != this) {
    // Not running: apply now (step commands run their iterations here). If the thread starts
    // meanwhile, whoever locks first applies it. From inside a StepSync callback it stays
    // queued for the next iteration.
    std::lock_guard<std::mutex> lock(step_mutex_);
    try {
      {
        IteratingScope scope(this);
        AfterPublishLocked(core_.ApplyPending(), false);
      }
      while (core_.stepping()) IterateLocked({.force_step = false, .honour_error_latch = false});
    } catch (const std::exception& e) {
      FailLocked(e);
      throw;
    }
  } else {
    wake_cv_.notify_one();  // a paused loop sleeping until the next period
  }
  return seq;
}

void PhysicsEngine::CancelStepsThrough(std::uint64_t seq) {
  core_.CancelStepsThrough(seq);
  wake_cv_.notify_one();  // a paused loop applies the queue (and drops the cancelled) at once
}

CommandResult PhysicsEngine::WaitForCommand(std::uint64_t seq,
                                            std::chrono::steady_clock::duration timeout) {
  ThrowIfOnPhysicsThread("WaitForCommand");
  return core_.commands().Wait(seq, timeout);
}

std::uint64_t PhysicsEngine::Reset() { return Submit(cmd::Reset{}); }

std::uint64_t PhysicsEngine::ResetToKeyframe(int key) { return Submit(cmd::ResetKeyframe{key}); }

std::uint64_t PhysicsEngine::ResetToKeyframe(const std::string& name) {
  const int key = mj_name2id(core_.model(), mjOBJ_KEY, name.c_str());
  if (key < 0) throw Error("ResetToKeyframe: no keyframe named '" + name + "'");
  return ResetToKeyframe(key);
}

std::uint64_t PhysicsEngine::ResetWith(StepCallback fn, std::string label) {
  return Submit(cmd::ResetCustom{std::move(fn), std::move(label)});
}

std::uint64_t PhysicsEngine::Restore(PhysicsState state) {
  return Submit(cmd::Restore{std::move(state)});
}

PhysicsState PhysicsEngine::Snapshot() {
  ThrowIfOnPhysicsThread("Snapshot");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return CaptureState(core_.model(), core_.data());
}

void PhysicsEngine::StepSync(int n) {
  ThrowIfOnPhysicsThread("StepSync");
  if (running() && !paused()) {
    throw Error("StepSync: the physics loop is running; pause it first");
  }
  for (int i = 0; i < n; ++i) {
    std::lock_guard<std::mutex> lock(step_mutex_);
    try {
      IterateLocked({.force_step = true, .honour_error_latch = false});
    } catch (const std::exception& e) {
      FailLocked(e);
      throw;
    }
  }
}

void PhysicsEngine::SetPaused(bool paused) {
  core_.SetPaused(paused);
  if (!paused) wake_cv_.notify_one();
}

void PhysicsEngine::TogglePause() {
  core_.TogglePause();
  wake_cv_.notify_one();
}

void PhysicsEngine::SetSpeedPercent(int percent) {
  speed_percent_.store(std::clamp(percent, 5, 100), std::memory_order_relaxed);
}

void PhysicsEngine::SetTargetInterval(double seconds) {
  follow_timestep_.store(!(seconds > 0), std::memory_order_relaxed);
  if (seconds > 0) target_interval_.store(seconds, std::memory_order_relaxed);
}

// ---------------------------------------------------------------------------------------------
// Events

void PhysicsEngine::OnEvent(EngineEvent e) {
  if (log_events_) {
    if (e.kind == EngineEventKind::kError) {
      spdlog::error("{}", e.message);
    } else if (e.kind == EngineEventKind::kDivergence) {
      const auto now = clock_->now();
      if (now - last_divergence_log_ > std::chrono::seconds(1)) {  // a broken model diverges often
        spdlog::warn("{}", Describe(e));
        last_divergence_log_ = now;
      }
    }
  }
  QueueEvent(std::move(e));
}

void PhysicsEngine::QueueEvent(EngineEvent event) {
  std::lock_guard<std::mutex> lock(events_mutex_);
  if (events_.size() >= kMaxQueuedEvents) {
    events_.pop_front();
    dropped_events_.fetch_add(1, std::memory_order_relaxed);
  }
  events_.push_back(std::move(event));
}

std::vector<EngineEvent> PhysicsEngine::DrainEvents() {
  std::lock_guard<std::mutex> lock(events_mutex_);
  std::vector<EngineEvent> out(std::make_move_iterator(events_.begin()),
                               std::make_move_iterator(events_.end()));
  events_.clear();
  return out;
}

int PhysicsEngine::PollEvents() {
  std::vector<EngineEvent> events = DrainEvents();
  std::vector<EventListener> listeners;
  {
    std::lock_guard<std::mutex> lock(events_mutex_);
    for (const auto& [id, fn] : listeners_) listeners.push_back(fn);
  }
  for (const EngineEvent& e : events) {
    for (const EventListener& fn : listeners) fn(e);
  }
  return static_cast<int>(events.size());
}

PhysicsEngine::CallbackId PhysicsEngine::AddEventListener(EventListener fn) {
  if (!fn) throw Error("AddEventListener: empty listener");
  std::lock_guard<std::mutex> lock(events_mutex_);
  const CallbackId id = next_listener_id_++;
  listeners_.emplace_back(id, std::move(fn));
  return id;
}

// ---------------------------------------------------------------------------------------------
// The iteration and the loop

StepCore::Iteration PhysicsEngine::IterateLocked(StepCore::AdvanceOptions options, bool from_loop) {
  StepCore::Iteration it;
  {
    IteratingScope scope(this);
    it = core_.Advance(options);
  }
  AfterPublishLocked(it, from_loop && it.stepped && !core_.stepping() && !it.window_ended &&
                             as_fast_.load(std::memory_order_relaxed));
  return it;
}

void PhysicsEngine::FailLocked(const std::exception& e) {
  AfterPublishLocked(core_.Fail(e), false);
}

void PhysicsEngine::AfterPublishLocked(const StepCore::Iteration& it, bool may_coalesce) {
  if (!it.published) return;
  // With `may_coalesce` (a free-running iteration as fast as possible) the ring is skipped when
  // the last one was less than kRingCoalesce ago and nothing else is due (finished commands, a
  // pause): the consumers then take several frames per wake-up, and the loop rings before it
  // would idle.
  if (!may_coalesce || it.urgent || SteadyClock::now() - last_ring_ >= kRingCoalesce) {
    RingDoorbellsLocked();
  } else {
    unrung_ = true;
  }
}

void PhysicsEngine::RingDoorbellsLocked() {
  for (const auto& bell : doorbells_) bell->Ring();
  last_ring_ = SteadyClock::now();
  unrung_ = false;
}

void PhysicsEngine::Loop() {
  bool window_ended = false;  // a lockstep window ended in the last iteration
  SpinWait spin;              // for the next lockstep request (gives up under CPU contention)
  Clock& clock = *clock_;
  auto next = clock.now();
  auto window_start = next;
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    core_.TakeProgress();
  }
  while (!stop_.load(std::memory_order_acquire)) {
    const bool paused_now = paused();
    bool stepping = false;  // a lockstep window is under way (or commands wait behind one)
    {
      std::lock_guard<std::mutex> lock(step_mutex_);
      window_ended = false;
      try {
        window_ended = IterateLocked({}, /*from_loop=*/true).window_ended;
      } catch (const std::exception& e) {
        FailLocked(e);
      }
      const auto now = clock.now();
      const double window = std::chrono::duration<double>(now - window_start).count();
      if (window >= measure_window_) {
        const StepCore::Progress p = core_.TakeProgress();
        rtf_.store(paused_now ? 0.0 : p.sim_seconds / window, std::memory_order_relaxed);
        step_rate_.store(static_cast<double>(p.steps) / window, std::memory_order_relaxed);
        window_start = now;
      }
      stepping = core_.stepping();
      // A frame published without a ring is announced before the loop could wait.
      if (unrung_ && !(as_fast_.load(std::memory_order_relaxed) && !paused())) {
        RingDoorbellsLocked();
      }
    }
    if (stepping || (as_fast_.load(std::memory_order_relaxed) && !paused_now)) {
      next = clock.now();  // lockstep windows and as-fast-as-possible run without pacing
      continue;
    }
    if (paused_now) {
      // Lockstep: the next request usually follows within a round trip of the last window, so
      // wait for it briefly without sleeping (a futex wake-up costs more than the round trip).
      const CommandQueue& queue = core_.commands();
      if (window_ended) {
        spin.Spin(kLockstepSpin, [&] {
          return queue.pending() || !paused() || stop_.load(std::memory_order_relaxed);
        });
        if (queue.pending() || !paused()) continue;
      }
      // Paused: sleep until a command arrives (lockstep requests wake the loop at once).
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_cv_.wait_for(lock, kMaxSleep, [&] {
        return queue.pending() || !paused() || stop_.load(std::memory_order_relaxed);
      });
      next = clock.now();
      continue;
    }
    const double period =
        target_interval() * 100.0 / speed_percent_.load(std::memory_order_relaxed);
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period));
    auto now = clock.now();
    if (now - next > std::chrono::duration<double>(resync_threshold_)) {
      next = now;  // far behind: restart the schedule instead of bursting to catch up
      continue;
    }
    while (now < next && !stop_.load(std::memory_order_relaxed)) {
      clock.sleep_until(std::min<Clock::time_point>(next, now + kMaxSleep));
      now = clock.now();
    }
  }
}

}  // namespace urlab::physics
