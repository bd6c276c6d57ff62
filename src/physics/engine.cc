#include "urlab/physics/engine.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

using Clock = std::chrono::steady_clock;

// MuJoCo's instability warnings watched after every step, with whether the info is a qpos index.
constexpr std::array<int, 3> kWatchedWarnings = {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC};
constexpr std::array<const char*, 3> kWatchedNames = {"qpos", "qvel", "qacc"};

// Below this much remaining wait the loop yields instead of sleeping (sleep overshoots).
constexpr auto kSpinMargin = std::chrono::microseconds(200);
// Longest single sleep, so that Stop() is honoured promptly even with long intervals.
constexpr auto kMaxSleep = std::chrono::milliseconds(20);

int FirstBad(const mjtNum* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return i;
  }
  return -1;
}

std::string Describe(const EngineEvent& e) {
  std::string s = e.message;
  if (e.joint_id >= 0) {
    s += " (joint " + (e.joint_name.empty() ? "#" + std::to_string(e.joint_id) : e.joint_name);
    if (!e.articulation.empty()) s += ", articulation " + e.articulation;
    s += ")";
  }
  return s;
}

}  // namespace

namespace {
// The engine whose iteration the current thread is running (set while callbacks may run).
thread_local const PhysicsEngine* tls_iterating = nullptr;

struct IteratingScope {
  explicit IteratingScope(const PhysicsEngine* e) : saved(tls_iterating) { tls_iterating = e; }
  ~IteratingScope() { tls_iterating = saved; }
  const PhysicsEngine* saved;
};
}  // namespace

// ---------------------------------------------------------------------------------------------
// RenderBuffer

RenderBuffer::RenderBuffer(int nbody) {
  for (auto& s : slots_) {
    s.xpos.assign(static_cast<std::size_t>(3 * nbody), 0);
    s.xquat.assign(static_cast<std::size_t>(4 * nbody), 0);
  }
}

void RenderBuffer::Publish() {
  back_ = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) & kIndex;
}

const RenderSnapshot* RenderBuffer::Latest() {
  if (middle_.load(std::memory_order_acquire) & kFresh) {
    front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    has_front_ = true;
  }
  return has_front_ ? &slots_[front_] : nullptr;
}

// ---------------------------------------------------------------------------------------------
// PhysicsEngine: construction and lifecycle

PhysicsEngine::PhysicsEngine(ModelPtr model) : PhysicsEngine(std::move(model), Options{}) {}

PhysicsEngine::PhysicsEngine(ModelPtr model, Options options)
    : model_(std::move(model)), render_(model_ ? model_->nbody : 0) {
  if (!model_) throw Error("PhysicsEngine needs a compiled model");
  data_ = MakeData(model_.get());
  mj_forward(model_.get(), data_.get());
  SetSpeedPercent(options.speed_percent);
  SetTargetInterval(options.target_interval);
  as_fast_.store(options.as_fast_as_possible);
  reset_on_divergence_.store(options.reset_on_divergence);
  resync_threshold_ = options.resync_threshold;
  log_events_ = options.log_events;
  measure_window_ = options.measure_window > 0 ? options.measure_window : 0.25;
  qpos_joint_.assign(static_cast<std::size_t>(model_->nq), -1);
  for (int j = 0; j < model_->njnt; ++j) {
    const int next = j + 1 < model_->njnt ? model_->jnt_qposadr[j + 1] : model_->nq;
    for (int i = model_->jnt_qposadr[j]; i < next; ++i)
      qpos_joint_[static_cast<std::size_t>(i)] = j;
  }
  PublishRenderLocked();
}

PhysicsEngine::~PhysicsEngine() { Stop(); }

void PhysicsEngine::Start() {
  ThrowIfOnPhysicsThread("Start");
  if (running_.load()) throw Error("PhysicsEngine::Start: the physics thread is already running");
  stop_.store(false);
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { Loop(); });
}

void PhysicsEngine::Stop() {
  if (!thread_.joinable()) return;
  ThrowIfOnPhysicsThread("Stop");
  stop_.store(true, std::memory_order_release);
  thread_.join();
  running_.store(false, std::memory_order_release);
  // Commands queued while the thread was winding down are applied now.
  std::lock_guard<std::mutex> lock(step_mutex_);
  ApplyPendingLocked();
}

void PhysicsEngine::WithLockedData(const std::function<void(mjModel*, mjData*)>& fn) {
  ThrowIfOnPhysicsThread("WithLockedData");
  std::lock_guard<std::mutex> lock(step_mutex_);
  fn(model_.get(), data_.get());
}

void PhysicsEngine::ThrowIfOnPhysicsThread(const char* what) const {
  if (tls_iterating == this) {
    throw Error(std::string("PhysicsEngine::") + what +
                " called from inside a step callback (would deadlock)");
  }
}

// ---------------------------------------------------------------------------------------------
// Hooks

PhysicsEngine::CallbackId PhysicsEngine::AddHook(std::vector<Hook>* hooks, StepCallback fn) {
  ThrowIfOnPhysicsThread("Add*Callback");
  if (!fn) throw Error("PhysicsEngine: empty callback");
  std::lock_guard<std::mutex> lock(step_mutex_);
  const CallbackId id = next_id_++;
  hooks->push_back({id, std::move(fn)});
  return id;
}

PhysicsEngine::CallbackId PhysicsEngine::AddPreStepCallback(StepCallback fn) {
  return AddHook(&pre_step_, std::move(fn));
}
PhysicsEngine::CallbackId PhysicsEngine::AddPostStepCallback(StepCallback fn) {
  return AddHook(&post_step_, std::move(fn));
}
PhysicsEngine::CallbackId PhysicsEngine::AddOnPostStep(StepCallback fn) {
  return AddHook(&on_post_step_, std::move(fn));
}

bool PhysicsEngine::RemoveCallback(CallbackId id) {
  ThrowIfOnPhysicsThread("RemoveCallback");
  std::lock_guard<std::mutex> lock(step_mutex_);
  for (auto* hooks : {&pre_step_, &post_step_, &on_post_step_}) {
    auto it =
        std::find_if(hooks->begin(), hooks->end(), [id](const Hook& h) { return h.id == id; });
    if (it != hooks->end()) {
      hooks->erase(it);
      return true;
    }
  }
  return false;
}

void PhysicsEngine::SetApplyControlsHook(StepCallback fn) {
  ThrowIfOnPhysicsThread("SetApplyControlsHook");
  std::lock_guard<std::mutex> lock(step_mutex_);
  apply_controls_ = std::move(fn);
}

void PhysicsEngine::SetCustomStepHandler(StepCallback fn) {
  ThrowIfOnPhysicsThread("SetCustomStepHandler");
  std::lock_guard<std::mutex> lock(step_mutex_);
  custom_step_ = std::move(fn);
}

void PhysicsEngine::SetArticulationResolver(ArticulationResolver fn) {
  ThrowIfOnPhysicsThread("SetArticulationResolver");
  std::lock_guard<std::mutex> lock(step_mutex_);
  resolver_ = std::move(fn);
}

// ---------------------------------------------------------------------------------------------
// Commands

void PhysicsEngine::QueueReset(PendingReset reset) {
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    pending_reset_ = std::move(reset);
    has_pending_.store(true, std::memory_order_release);
  }
  if (!running() && tls_iterating != this) {
    // Not running: apply now. If the thread starts meanwhile, whoever locks first applies it.
    // From inside a StepSync callback it stays queued for the next iteration.
    std::lock_guard<std::mutex> lock(step_mutex_);
    ApplyPendingLocked();
  }
}

void PhysicsEngine::Reset() { QueueReset(PendingReset{}); }

void PhysicsEngine::ResetToKeyframe(int key) {
  if (key < 0 || key >= model_->nkey) {
    throw Error("ResetToKeyframe: keyframe id " + std::to_string(key) +
                " out of range (model has " + std::to_string(model_->nkey) + ")");
  }
  PendingReset r;
  r.kind = PendingReset::Kind::kKeyframe;
  r.key = key;
  QueueReset(std::move(r));
}

void PhysicsEngine::ResetToKeyframe(const std::string& name) {
  const int key = mj_name2id(model_.get(), mjOBJ_KEY, name.c_str());
  if (key < 0) throw Error("ResetToKeyframe: no keyframe named '" + name + "'");
  ResetToKeyframe(key);
}

void PhysicsEngine::ResetWith(StepCallback fn, std::string label) {
  if (!fn) throw Error("ResetWith: empty reset function");
  PendingReset r;
  r.kind = PendingReset::Kind::kCustom;
  r.fn = std::move(fn);
  r.label = std::move(label);
  QueueReset(std::move(r));
}

PhysicsState PhysicsEngine::Snapshot() {
  ThrowIfOnPhysicsThread("Snapshot");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return CaptureState(model_.get(), data_.get());
}

void PhysicsEngine::Restore(PhysicsState state) {
  const StateLayout expected = StateLayout::Of(model_.get());
  if (!(state.layout == expected)) {
    throw StateError("Restore: state has " + state.layout.str() + ", model has " + expected.str());
  }
  if (!state.IsConsistent()) throw StateError("Restore: state arrays do not match their layout");
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    pending_restore_ = std::move(state);
    has_pending_.store(true, std::memory_order_release);
  }
  if (!running() && tls_iterating != this) {
    std::lock_guard<std::mutex> lock(step_mutex_);
    ApplyPendingLocked();
  }
}

void PhysicsEngine::StepSync(int n) {
  ThrowIfOnPhysicsThread("StepSync");
  if (running() && !paused()) {
    throw Error("StepSync: the physics loop is running; pause it first");
  }
  for (int i = 0; i < n; ++i) {
    std::lock_guard<std::mutex> lock(step_mutex_);
    try {
      IterateLocked(/*force_step=*/true);
    } catch (const std::exception& e) {
      HandleErrorLocked(e);
      throw;
    }
  }
}

void PhysicsEngine::SetPaused(bool paused) {
  if (!paused) error_latched_.store(false, std::memory_order_release);
  paused_.store(paused, std::memory_order_release);
}

void PhysicsEngine::TogglePause() {
  bool expected = paused_.load();
  while (!paused_.compare_exchange_weak(expected, !expected)) {
  }
  if (expected) error_latched_.store(false, std::memory_order_release);
}

void PhysicsEngine::SetSpeedPercent(int percent) {
  speed_percent_.store(std::clamp(percent, 5, 100), std::memory_order_relaxed);
}

void PhysicsEngine::SetTargetInterval(double seconds) {
  target_interval_.store(seconds > 0 ? seconds : model_->opt.timestep, std::memory_order_relaxed);
}

// ---------------------------------------------------------------------------------------------
// Events

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
// The iteration

void PhysicsEngine::ApplyResetLocked(const PendingReset& reset) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  EngineEvent e;
  e.kind = EngineEventKind::kReset;
  e.sim_time = d->time;
  switch (reset.kind) {
    case PendingReset::Kind::kFull:
      mj_resetData(m, d);
      e.message = "reset";
      break;
    case PendingReset::Kind::kKeyframe:
      mj_resetDataKeyframe(m, d, reset.key);
      e.message = "reset to keyframe " + std::to_string(reset.key);
      if (const char* name = mj_id2name(m, mjOBJ_KEY, reset.key); name && name[0]) {
        e.message += " '" + std::string(name) + "'";
      }
      break;
    case PendingReset::Kind::kCustom:
      reset.fn(m, d);
      e.message = reset.label.empty() ? "custom reset" : reset.label;
      break;
  }
  mj_forward(m, d);
  in_divergence_ = false;
  QueueEvent(std::move(e));
}

void PhysicsEngine::ApplyPendingLocked() {
  if (!has_pending_.load(std::memory_order_acquire)) return;
  IteratingScope scope(this);
  std::optional<PendingReset> reset;
  std::optional<PhysicsState> restore;
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    reset.swap(pending_reset_);
    restore.swap(pending_restore_);
    has_pending_.store(false, std::memory_order_release);
  }
  if (reset) ApplyResetLocked(*reset);
  if (restore) {
    const double before = data_->time;
    RestoreState(model_.get(), data_.get(), *restore);
    in_divergence_ = false;
    QueueEvent({EngineEventKind::kRestored, before,
                "restored state at t=" + std::to_string(restore->time)});
  }
  if (reset || restore) PublishRenderLocked();
}

void PhysicsEngine::IterateLocked(bool force_step) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  IteratingScope scope(this);
  ApplyPendingLocked();
  for (const Hook& h : pre_step_) h.fn(m, d);
  if (apply_controls_) apply_controls_(m, d);
  const bool step = force_step || !paused_.load(std::memory_order_acquire);
  if (step) {
    const double time_before = d->time;
    for (std::size_t i = 0; i < kWatchedWarnings.size(); ++i) {
      d->warning[kWatchedWarnings[i]].lastinfo = -1;  // sentinel: MuJoCo sets it on a warning
    }
    if (custom_step_) {
      custom_step_(m, d);
    } else {
      mj_step(m, d);
    }
    step_count_.fetch_add(1, std::memory_order_relaxed);
    if (d->time > time_before) sim_advanced_ += d->time - time_before;
    ++window_steps_;
    CheckDivergenceLocked(time_before);
  }
  for (const Hook& h : post_step_) h.fn(m, d);
  if (step) {
    for (const Hook& h : on_post_step_) h.fn(m, d);
    PublishRenderLocked();
  }
}

int PhysicsEngine::JointOfIndex(int index, bool is_qpos) const {
  if (is_qpos) {
    return index >= 0 && index < model_->nq ? qpos_joint_[static_cast<std::size_t>(index)] : -1;
  }
  return index >= 0 && index < model_->nv ? model_->dof_jntid[index] : -1;
}

void PhysicsEngine::CheckDivergenceLocked(double time_before) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  const char* what = nullptr;
  int joint = -1;
  // MuJoCo's own checks (which also reset mjData) report through the warning statistics.
  for (std::size_t i = 0; i < kWatchedWarnings.size() && !what; ++i) {
    const mjWarningStat& w = d->warning[kWatchedWarnings[i]];
    // mj_resetData (which MuJoCo calls after the warning) zeroes every statistic and then
    // re-raises the offending one, so only a raised counter with a fresh lastinfo counts.
    if (w.number > 0 && w.lastinfo != -1) {
      what = kWatchedNames[i];
      joint = JointOfIndex(w.lastinfo, kWatchedWarnings[i] == mjWARN_BADQPOS);
    }
  }
  // Non-finite values MuJoCo has not caught yet (e.g. written by a custom step handler).
  if (!what) {
    if (int i = FirstBad(d->qpos, m->nq); i >= 0) {
      what = "qpos";
      joint = JointOfIndex(i, true);
    } else if ((i = FirstBad(d->qvel, m->nv)) >= 0) {
      what = "qvel";
      joint = JointOfIndex(i, false);
    } else if ((i = FirstBad(d->qacc, m->nv)) >= 0) {
      what = "qacc";
      joint = JointOfIndex(i, false);
    }
  }
  if (!what) {
    in_divergence_ = false;
    return;
  }
  // One report per episode: repeated bad steps without recovery are not re-reported.
  if (in_divergence_) return;
  in_divergence_ = true;
  EngineEvent e;
  e.kind = EngineEventKind::kDivergence;
  e.sim_time = time_before;
  e.message =
      std::string("simulation diverged: bad ") + what + " at t=" + std::to_string(time_before);
  e.joint_id = joint;
  if (joint >= 0) {
    const char* name = mj_id2name(m, mjOBJ_JOINT, joint);
    e.joint_name = name ? name : "";
    if (resolver_ && !e.joint_name.empty()) e.articulation = resolver_(e.joint_name);
  }
  e.auto_reset = reset_on_divergence_.load(std::memory_order_relaxed);
  const auto now = Clock::now();
  if (log_events_ &&
      now - last_divergence_log_ > std::chrono::seconds(1)) {  // a broken model diverges often
    spdlog::warn("{}", Describe(e));
    last_divergence_log_ = now;
  }
  QueueEvent(e);
  if (e.auto_reset) {
    // Keep the warning statistics so MuJoCo does not print its warning again on every blow-up.
    mjWarningStat warnings[mjNWARNING];
    std::memcpy(warnings, d->warning, sizeof(warnings));
    mj_resetData(m, d);
    std::memcpy(d->warning, warnings, sizeof(warnings));
    mj_forward(m, d);
    in_divergence_ = false;
    QueueEvent({EngineEventKind::kReset, time_before, "reset after divergence"});
  }
}

void PhysicsEngine::PublishRenderLocked() {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  RenderSnapshot& s = render_.Back();
  s.time = d->time;
  s.step = step_count_.load(std::memory_order_relaxed);
  s.ncon = d->ncon;
  std::memcpy(s.xpos.data(), d->xpos, sizeof(mjtNum) * 3 * static_cast<std::size_t>(m->nbody));
  std::memcpy(s.xquat.data(), d->xquat, sizeof(mjtNum) * 4 * static_cast<std::size_t>(m->nbody));
  render_.Publish();
}

void PhysicsEngine::HandleErrorLocked(const std::exception& e) {
  // An error thrown out of MuJoCo leaves its stack pointer where it was; nothing of ours is on
  // the mjData stack between iterations, so it is safe to release it all.
  data_->pstack = 0;
  paused_.store(true, std::memory_order_release);
  error_latched_.store(true, std::memory_order_release);
  EngineEvent ev;
  ev.kind = EngineEventKind::kError;
  ev.sim_time = data_->time;
  ev.message = std::string("physics loop paused after an error: ") + e.what();
  if (log_events_) spdlog::error("{}", ev.message);
  QueueEvent(std::move(ev));
}

void PhysicsEngine::Loop() {
  auto next = Clock::now();
  auto window_start = next;
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    sim_advanced_ = 0;
    window_steps_ = 0;
  }
  while (!stop_.load(std::memory_order_acquire)) {
    const bool paused_now = paused();
    {
      std::lock_guard<std::mutex> lock(step_mutex_);
      try {
        if (error_latched_.load(std::memory_order_acquire) && paused()) {
          IteratingScope scope(this);
          ApplyPendingLocked();  // resets/restores still work; callbacks stay quiet
        } else {
          IterateLocked(/*force_step=*/false);
        }
      } catch (const std::exception& e) {
        HandleErrorLocked(e);
      }
      const auto now = Clock::now();
      const double window = std::chrono::duration<double>(now - window_start).count();
      if (window >= measure_window_) {
        rtf_.store(paused_now ? 0.0 : sim_advanced_ / window, std::memory_order_relaxed);
        step_rate_.store(static_cast<double>(window_steps_) / window, std::memory_order_relaxed);
        sim_advanced_ = 0;
        window_steps_ = 0;
        window_start = now;
      }
    }
    if (as_fast_.load(std::memory_order_relaxed) && !paused_now) {
      next = Clock::now();
      continue;
    }
    const double period = target_interval_.load(std::memory_order_relaxed) * 100.0 /
                          speed_percent_.load(std::memory_order_relaxed);
    next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period));
    auto now = Clock::now();
    if (now - next > std::chrono::duration<double>(resync_threshold_)) {
      next = now;  // far behind: restart the schedule instead of bursting to catch up
      continue;
    }
    while (now < next && !stop_.load(std::memory_order_relaxed)) {
      const auto remaining = next - now;
      if (remaining > kSpinMargin) {
        std::this_thread::sleep_for(std::min<Clock::duration>(remaining - kSpinMargin, kMaxSleep));
      } else {
        std::this_thread::yield();
      }
      now = Clock::now();
    }
  }
}

}  // namespace urlab::physics
