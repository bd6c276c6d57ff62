#include "urlab/physics/engine.h"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <variant>

#include "core/spin_wait.h"
#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

using Clock = std::chrono::steady_clock;

// MuJoCo's instability warnings watched after every step: what went bad, and what the warning's
// info indexes (a qpos address, a dof address or an actuator id).
enum class WarnIndex { kQpos, kDof, kActuator };
struct WatchedWarning {
  int warning;
  const char* what;
  WarnIndex index;
};
constexpr std::array<WatchedWarning, 4> kWatched = {{
    {mjWARN_BADQPOS, "qpos", WarnIndex::kQpos},
    {mjWARN_BADQVEL, "qvel", WarnIndex::kDof},
    {mjWARN_BADQACC, "qacc", WarnIndex::kDof},
    {mjWARN_BADCTRL, "ctrl", WarnIndex::kActuator},
}};

bool AllFinite(const mjtNum* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
  }
  return true;
}

// Below this much remaining wait the loop yields instead of sleeping (sleep overshoots).
constexpr auto kSpinMargin = std::chrono::microseconds(200);
// Longest single sleep, so that Stop() is honoured promptly even with long intervals.
constexpr auto kMaxSleep = std::chrono::milliseconds(20);
// How long a paused loop waits for the next lockstep request without sleeping.
constexpr auto kLockstepSpin = std::chrono::microseconds(500);
// Running as fast as possible, the doorbells are rung at most this often (see
// PublishFrameLocked): a consumer woken for every 30 µs step costs the loop more than it gains.
constexpr auto kRingCoalesce = std::chrono::microseconds(50);

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
// PhysicsEngine: construction and lifecycle

PhysicsEngine::PhysicsEngine(Model model) : PhysicsEngine(std::move(model), Options{}) {}

PhysicsEngine::PhysicsEngine(Model model, Options options)
    : model_(model ? std::move(model) : throw Error("PhysicsEngine needs a compiled model")),
      publisher_(model_.get()) {
  data_ = MakeData(model_.get());
  mj_forward(model_.get(), data_.get());
  SetSpeedPercent(options.speed_percent);
  timestep_.store(model_->opt.timestep);
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
  if (ApplyPendingLocked()) PublishFrameLocked();
  if (unrung_) RingDoorbellsLocked();
}

void PhysicsEngine::WithLockedData(const std::function<void(mjModel*, mjData*)>& fn) {
  ThrowIfOnPhysicsThread("WithLockedData");
  std::lock_guard<std::mutex> lock(step_mutex_);
  fn(model_.get(), data_.get());
}

Model PhysicsEngine::CopyModel() {
  ThrowIfOnPhysicsThread("CopyModel");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return model_.Copy();
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
  return std::erase_if(command_listeners_, [id](const auto& l) { return l.first == id; }) > 0;
}

void PhysicsEngine::SetApplyControlsHook(StepCallback fn) {
  ThrowIfOnPhysicsThread("SetApplyControlsHook");
  std::lock_guard<std::mutex> lock(step_mutex_);
  apply_controls_ = std::move(fn);
}

void PhysicsEngine::SetCommandLayout(std::vector<CommandGroupLayout> layout) {
  ThrowIfOnPhysicsThread("SetCommandLayout");
  std::lock_guard<std::mutex> lock(step_mutex_);
  applied_commands_ = AppliedCommands::SizedFor(layout);
  publisher_.SetCommandLayout(layout);
  command_layout_ = std::move(layout);
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

PhysicsEngine::CallbackId PhysicsEngine::AddCommandListener(CommandListener fn) {
  ThrowIfOnPhysicsThread("AddCommandListener");
  if (!fn) throw Error("PhysicsEngine: empty command listener");
  std::lock_guard<std::mutex> lock(step_mutex_);
  const CallbackId id = next_id_++;
  command_listeners_.emplace_back(id, std::move(fn));
  return id;
}

// ---------------------------------------------------------------------------------------------
// State readers

std::shared_ptr<StateSubscription> PhysicsEngine::SubscribeState(std::string name) {
  ThrowIfOnPhysicsThread("SubscribeState");
  if (running()) throw Error("SubscribeState('" + name + "'): subscribe before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  auto s = publisher_.SubscribeLatest(std::move(name));
  // The current state, so a reader has a frame before the first step (others get nothing new).
  FrameMeta meta;
  meta.step = step_count_.load(std::memory_order_relaxed);
  meta.frame = frames_;
  meta.command_seq = commands_.last_applied();
  meta.epoch = epoch_;
  meta.paused = paused();
  StatePublisher::PublishTo(*s, model_.get(), data_.get(), meta);
  return s;
}

std::shared_ptr<StateRing> PhysicsEngine::SubscribeEveryStep(std::string name,
                                                             std::size_t capacity) {
  ThrowIfOnPhysicsThread("SubscribeEveryStep");
  if (running()) throw Error("SubscribeEveryStep('" + name + "'): subscribe before Start");
  std::lock_guard<std::mutex> lock(step_mutex_);
  return publisher_.SubscribeEveryStep(std::move(name), capacity);
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
  return publisher_.Unsubscribe(subscription);
}

// ---------------------------------------------------------------------------------------------
// Commands

void PhysicsEngine::ValidateCommand(const Command& command) const {
  const mjModel* m = model_.get();
  const auto range = [](const char* what, int adr, std::size_t n, int size) {
    if (adr < 0 || n == 0 || static_cast<std::size_t>(adr) + n > static_cast<std::size_t>(size)) {
      throw Error(std::string(what) + ": " + std::to_string(n) + " value(s) at address " +
                  std::to_string(adr) + " do not fit the model's " + std::to_string(size));
    }
  };
  const auto finite = [](const char* what, const mjtNum* v, std::size_t n) {
    if (!AllFinite(v, n)) throw Error(std::string(what) + ": non-finite value");
  };
  std::visit(
      [&](const auto& c) {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, cmd::ResetKeyframe>) {
          if (c.key < 0 || c.key >= m->nkey) {
            throw Error("ResetToKeyframe: keyframe id " + std::to_string(c.key) +
                        " out of range (model has " + std::to_string(m->nkey) + ")");
          }
        } else if constexpr (std::is_same_v<T, cmd::ResetCustom>) {
          if (!c.fn) throw Error("ResetWith: empty reset function");
        } else if constexpr (std::is_same_v<T, cmd::Restore>) {
          const StateLayout expected = StateLayout::Of(m);
          if (!(c.state.layout == expected)) {
            throw StateError("Restore: state has " + c.state.layout.str() + ", model has " +
                             expected.str());
          }
          if (!c.state.IsConsistent()) {
            throw StateError("Restore: state arrays do not match their layout");
          }
        } else if constexpr (std::is_same_v<T, cmd::SetQpos>) {
          range("SetQpos", c.adr, c.values.size(), m->nq);
          finite("SetQpos", c.values.data(), c.values.size());
        } else if constexpr (std::is_same_v<T, cmd::SetQvel>) {
          range("SetQvel", c.adr, c.values.size(), m->nv);
          finite("SetQvel", c.values.data(), c.values.size());
        } else if constexpr (std::is_same_v<T, cmd::SetMocap>) {
          range("SetMocap", c.mocap_id, 1, m->nmocap);
          finite("SetMocap", c.pos.data(), 3);
          finite("SetMocap", c.quat.data(), 4);
          if (mju_norm(c.quat.data(), 4) < 1e-12) throw Error("SetMocap: zero quaternion");
        } else if constexpr (std::is_same_v<T, cmd::ApplyForce>) {
          range("ApplyForce", c.body, 1, m->nbody);
          if (c.steps < 1) throw Error("ApplyForce: steps must be at least 1");
          finite("ApplyForce", c.force.data(), 3);
          finite("ApplyForce", c.torque.data(), 3);
        } else if constexpr (std::is_same_v<T, cmd::SetOptions>) {
          if (!c.fn) throw Error("SetOptions: empty function");
        } else if constexpr (std::is_same_v<T, cmd::Inspect>) {
          if (!c.fn) throw Error("Inspect: empty function");
        } else if constexpr (std::is_same_v<T, cmd::SetState>) {
          const auto runs = [&](const char* what, const auto& rs, int size) {
            for (const auto& run : rs) {
              range(what, run.adr, run.values.size(), size);
              finite(what, run.values.data(), run.values.size());
            }
          };
          runs("SetState qpos", c.qpos, m->nq);
          runs("SetState qvel", c.qvel, m->nv);
          runs("SetState ctrl", c.ctrl, m->nu);
          if (c.time && !std::isfinite(*c.time)) throw Error("SetState: non-finite time");
        } else if constexpr (std::is_same_v<T, cmd::Step>) {
          if (c.n < 1 || c.n > 10'000'000) {
            throw Error("Step: n must be 1..10000000 (got " + std::to_string(c.n) + ")");
          }
        }
      },
      command);
}

std::uint64_t PhysicsEngine::Submit(Command command) {
  ValidateCommand(command);
  const std::uint64_t seq = commands_.Push(std::move(command));
  if (!running() && tls_iterating != this) {
    // Not running: apply now (step commands run their iterations here). If the thread starts
    // meanwhile, whoever locks first applies it. From inside a StepSync callback it stays
    // queued for the next iteration.
    std::lock_guard<std::mutex> lock(step_mutex_);
    try {
      if (ApplyPendingLocked()) PublishFrameLocked();
      while (step_budget_ > 0 || !backlog_.empty()) IterateLocked(/*force_step=*/false);
    } catch (const std::exception& e) {
      HandleErrorLocked(e);
      throw;
    }
  } else {
    wake_cv_.notify_one();  // a paused loop sleeping until the next period
  }
  return seq;
}

void PhysicsEngine::CancelStepsThrough(std::uint64_t seq) {
  std::uint64_t now = cancel_steps_through_.load(std::memory_order_relaxed);
  while (now < seq && !cancel_steps_through_.compare_exchange_weak(now, seq)) {
  }
  wake_cv_.notify_one();  // a paused loop applies the queue (and drops the cancelled) at once
}

CommandResult PhysicsEngine::WaitForCommand(std::uint64_t seq,
                                            std::chrono::steady_clock::duration timeout) {
  ThrowIfOnPhysicsThread("WaitForCommand");
  return commands_.Wait(seq, timeout);
}

std::uint64_t PhysicsEngine::Reset() { return Submit(cmd::Reset{}); }

std::uint64_t PhysicsEngine::ResetToKeyframe(int key) { return Submit(cmd::ResetKeyframe{key}); }

std::uint64_t PhysicsEngine::ResetToKeyframe(const std::string& name) {
  const int key = mj_name2id(model_.get(), mjOBJ_KEY, name.c_str());
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
  return CaptureState(model_.get(), data_.get());
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
  if (!paused) wake_cv_.notify_one();
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
  follow_timestep_.store(!(seconds > 0), std::memory_order_relaxed);
  target_interval_.store(seconds > 0 ? seconds : timestep(), std::memory_order_relaxed);
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

std::uint32_t PhysicsEngine::ApplyCommandLocked(Command& command) {
  mjModel* m = model_.get();
  mjData* d = data_.get();
  const auto reset_event = [&](double before, std::string message) {
    in_divergence_ = false;
    QueueEvent({EngineEventKind::kReset, before, std::move(message)});
  };
  const double before = d->time;
  const std::uint32_t what = std::visit(
      [&](auto& c) -> std::uint32_t {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, cmd::Reset>) {
          mj_resetData(m, d);
          mj_forward(m, d);
          reset_event(before, "reset");
          return kDiscontinuityReset;
        } else if constexpr (std::is_same_v<T, cmd::ResetKeyframe>) {
          mj_resetDataKeyframe(m, d, c.key);
          mj_forward(m, d);
          std::string msg = "reset to keyframe " + std::to_string(c.key);
          if (const char* name = mj_id2name(m, mjOBJ_KEY, c.key); name && name[0]) {
            msg += " '" + std::string(name) + "'";
          }
          reset_event(before, std::move(msg));
          return kDiscontinuityReset;
        } else if constexpr (std::is_same_v<T, cmd::ResetCustom>) {
          c.fn(m, d);
          mj_forward(m, d);
          reset_event(before, c.label.empty() ? "custom reset" : c.label);
          return kDiscontinuityReset;
        } else if constexpr (std::is_same_v<T, cmd::Restore>) {
          RestoreState(m, d, c.state);
          in_divergence_ = false;
          QueueEvent({EngineEventKind::kRestored, before,
                      "restored state at t=" + std::to_string(c.state.time)});
          return kDiscontinuityRestore;
        } else if constexpr (std::is_same_v<T, cmd::SetQpos>) {
          std::copy(c.values.begin(), c.values.end(), d->qpos + c.adr);
          mj_forward(m, d);
          return kDiscontinuitySetState;
        } else if constexpr (std::is_same_v<T, cmd::SetQvel>) {
          std::copy(c.values.begin(), c.values.end(), d->qvel + c.adr);
          mj_forward(m, d);
          return kDiscontinuitySetState;
        } else if constexpr (std::is_same_v<T, cmd::SetMocap>) {
          mju_copy3(d->mocap_pos + 3 * c.mocap_id, c.pos.data());
          mju_copy4(d->mocap_quat + 4 * c.mocap_id, c.quat.data());
          mju_normalize4(d->mocap_quat + 4 * c.mocap_id);
          return kNoDiscontinuity;
        } else if constexpr (std::is_same_v<T, cmd::ApplyForce>) {
          one_shot_.push_back(c);  // added right before the next step, removed after it
          return kNoDiscontinuity;
        } else if constexpr (std::is_same_v<T, cmd::SetOptions>) {
          const mjOption saved = m->opt;
          c.fn(m->opt);
          if (!(m->opt.timestep > 0) || !std::isfinite(m->opt.timestep)) {
            m->opt = saved;
            throw Error("SetOptions: timestep must be a positive finite number");
          }
          timestep_.store(m->opt.timestep, std::memory_order_relaxed);
          if (follow_timestep_.load(std::memory_order_relaxed)) {
            target_interval_.store(m->opt.timestep, std::memory_order_relaxed);  // real time
          }
          return kDiscontinuityOptions;
        } else if constexpr (std::is_same_v<T, cmd::SetPaused>) {
          SetPaused(c.paused);
          return kNoDiscontinuity;
        } else if constexpr (std::is_same_v<T, cmd::Forward>) {
          mj_forward(m, d);
          return kNoDiscontinuity;
        } else if constexpr (std::is_same_v<T, cmd::SetState>) {
          for (const auto& run : c.qpos)
            std::copy(run.values.begin(), run.values.end(), d->qpos + run.adr);
          for (const auto& run : c.qvel)
            std::copy(run.values.begin(), run.values.end(), d->qvel + run.adr);
          for (const auto& run : c.ctrl)
            std::copy(run.values.begin(), run.values.end(), d->ctrl + run.adr);
          if (c.time) d->time = *c.time;
          mj_forward(m, d);
          return kDiscontinuitySetState;
        } else if constexpr (std::is_same_v<T, cmd::Inspect>) {
          c.fn(m, d);
          return kNoDiscontinuity;
        } else {
          static_assert(std::is_same_v<T, cmd::Step>);  // handled by ApplyPendingLocked
          return kNoDiscontinuity;
        }
      },
      command);
  // A reset or restore also cancels forces still waiting for their step.
  if (what & (kDiscontinuityReset | kDiscontinuityRestore)) one_shot_.clear();
  return what;
}

bool PhysicsEngine::ApplyPendingLocked() {
  if (step_budget_ > 0) return false;  // a step command runs first; the rest waits behind it
  if (!commands_.pending() && backlog_.empty()) return false;
  IteratingScope scope(this);
  commands_.TakeAll(&backlog_);
  bool any = false;
  while (!backlog_.empty() && step_budget_ == 0) {
    CommandQueue::Entry e = std::move(backlog_.front());
    backlog_.pop_front();
    any = true;
    if (const auto* step = std::get_if<cmd::Step>(&e.command)) {
      if (e.seq <= cancel_steps_through_.load(std::memory_order_acquire)) {
        to_finish_.emplace_back(e.seq, std::string(kStepCancelled) + " before it ran");
        continue;
      }
      step_budget_ = step->n;  // finished by IterateLocked after its last iteration
      step_total_ = step->n;
      step_seq_ = e.seq;
      break;
    }
    AppliedCommand applied;
    applied.seq = e.seq;
    applied.name = CommandName(e.command);
    try {
      applied.discontinuity = ApplyCommandLocked(e.command);
    } catch (const std::exception& ex) {
      // The command did not take effect (or only partly: a custom reset that threw); the state
      // is recomputed so the loop goes on from something consistent.
      applied.error = std::string(applied.name) + ": " + ex.what();
      data_->pstack = 0;
      mj_forward(model_.get(), data_.get());
      if (log_events_) spdlog::warn("physics: command failed: {}", applied.error);
    }
    if (applied.discontinuity) {
      pending_discontinuity_ |= applied.discontinuity;
      ++epoch_;
    }
    for (const auto& [id, fn] : command_listeners_) fn(applied, model_.get(), data_.get());
    to_finish_.emplace_back(e.seq, std::move(applied.error));
  }
  return any;
}

void PhysicsEngine::FinishCommandsLocked() {
  for (auto& [seq, error] : to_finish_) commands_.Finish(seq, std::move(error));
  to_finish_.clear();
}

void PhysicsEngine::IterateLocked(bool force_step, bool from_loop) {
  const mjModel* m = model_.get();
  mjData* d = data_.get();
  IteratingScope scope(this);
  bool applied = ApplyPendingLocked();
  if (step_budget_ > 0 && step_seq_ <= cancel_steps_through_.load(std::memory_order_acquire)) {
    // The running step command was cancelled: its window ends here, the commands behind it go on.
    to_finish_.emplace_back(step_seq_, std::string(kStepCancelled) + " after " +
                                           std::to_string(step_total_ - step_budget_) + " of " +
                                           std::to_string(step_total_) + " steps");
    step_budget_ = 0;
    window_ended_ = true;
    ApplyPendingLocked();
    applied = true;
  }
  for (const Hook& h : pre_step_) h.fn(m, d);
  const bool budgeted = step_budget_ > 0;
  const bool step = force_step || budgeted || !paused_.load(std::memory_order_acquire);
  // Controls are written for a step only: while paused d->ctrl keeps what a command wrote (a
  // puppet client's ctrl, a restored state's).
  if (apply_controls_ && step) apply_controls_(m, d);
  if (step) {
    const double time_before = d->time;
    for (const WatchedWarning& w : kWatched) {
      d->warning[w.warning].lastinfo = -1;  // sentinel: MuJoCo sets it on a warning
    }
    one_shot_saved_.clear();
    for (const cmd::ApplyForce& f : one_shot_) {
      const bool saved = std::any_of(one_shot_saved_.begin(), one_shot_saved_.end(),
                                     [&](const auto& row) { return row.first == f.body; });
      if (!saved) {
        std::array<mjtNum, 6> row;
        std::copy_n(d->xfrc_applied + 6 * f.body, 6, row.begin());
        one_shot_saved_.emplace_back(f.body, row);
      }
      mju_addTo3(d->xfrc_applied + 6 * f.body, f.force.data());
      mju_addTo3(d->xfrc_applied + 6 * f.body + 3, f.torque.data());
    }
    one_shot_added_ = !one_shot_.empty();
    if (one_shot_added_) {  // the frame reports what this step used
      stepped_xfrc_.assign(d->xfrc_applied, d->xfrc_applied + 6 * m->nbody);
      stepped_xfrc_valid_ = true;
    }
    if (custom_step_) {
      custom_step_(m, d);
    } else {
      mj_step(m, d);
    }
    RemoveOneShotForcesLocked(/*all=*/false);  // each acts for its number of steps only
    step_count_.fetch_add(1, std::memory_order_relaxed);
    if (d->time > time_before) sim_advanced_ += d->time - time_before;
    ++window_steps_;
    CheckDivergenceLocked(time_before);
  }
  for (const Hook& h : post_step_) h.fn(m, d);
  if (step) {
    for (const Hook& h : on_post_step_) h.fn(m, d);
  }
  if (budgeted && --step_budget_ == 0) {  // the step command's last iteration
    window_ended_ = true;
    AppliedCommand done;
    done.seq = step_seq_;
    done.name = "step";
    for (const auto& [id, fn] : command_listeners_) fn(done, m, d);
    to_finish_.emplace_back(step_seq_, std::string());
  }
  last_iteration_stepped_ = step;
  if (step || applied || !to_finish_.empty() || published_paused_ != paused()) {
    PublishFrameLocked(/*may_coalesce=*/from_loop && step && !budgeted &&
                       as_fast_.load(std::memory_order_relaxed));
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
  int actuator = -1;
  // MuJoCo's own checks (which also reset mjData) report through the warning statistics.
  for (const WatchedWarning& watched : kWatched) {
    const mjWarningStat& w = d->warning[watched.warning];
    // mj_resetData (which MuJoCo calls after the warning) zeroes every statistic and then
    // re-raises the offending one, so only a raised counter with a fresh lastinfo counts.
    if (w.number > 0 && w.lastinfo != -1) {
      what = watched.what;
      if (watched.index == WarnIndex::kActuator) {
        actuator = w.lastinfo;
        if (actuator >= 0 && actuator < m->nu && m->actuator_trntype[actuator] == mjTRN_JOINT) {
          joint = m->actuator_trnid[2 * actuator];
        }
      } else {
        joint = JointOfIndex(w.lastinfo, watched.index == WarnIndex::kQpos);
      }
      break;
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
  if (actuator >= 0 && actuator < m->nu) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, actuator);
    e.message += " (actuator " + (name ? std::string(name) : "#" + std::to_string(actuator)) + ")";
  }
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
    pending_discontinuity_ |= kDiscontinuityReset;
    ++epoch_;
    QueueEvent({EngineEventKind::kReset, time_before, "reset after divergence"});
  }
}

void PhysicsEngine::RemoveOneShotForcesLocked(bool all) {
  if (one_shot_added_) {
    for (const auto& [body, row] : one_shot_saved_) {
      std::copy(row.begin(), row.end(), data_->xfrc_applied + 6 * body);
    }
    one_shot_saved_.clear();
  }
  one_shot_added_ = false;
  if (all) {
    one_shot_.clear();
    return;
  }
  for (cmd::ApplyForce& f : one_shot_) --f.steps;
  std::erase_if(one_shot_, [](const cmd::ApplyForce& f) { return f.steps <= 0; });
}

void PhysicsEngine::RingDoorbellsLocked() {
  for (const auto& bell : doorbells_) bell->Ring();
  last_ring_ = Clock::now();
  unrung_ = false;
}

void PhysicsEngine::PublishFrameLocked(bool may_coalesce) {
  FrameMeta meta;
  meta.step = step_count_.load(std::memory_order_relaxed);
  meta.frame = ++frames_;
  meta.command_seq = to_finish_.empty() ? commands_.last_applied() : to_finish_.back().first;
  meta.discontinuity = pending_discontinuity_;
  meta.epoch = epoch_;
  meta.paused = paused();
  meta.stepped = last_iteration_stepped_;
  meta.xfrc_applied =
      stepped_xfrc_valid_ && last_iteration_stepped_ ? stepped_xfrc_.data() : nullptr;
  meta.commands = applied_commands_.empty() ? nullptr : &applied_commands_;
  publisher_.Publish(model_.get(), data_.get(), meta);
  stepped_xfrc_valid_ = false;
  last_iteration_stepped_ = false;
  pending_discontinuity_ = 0;
  published_paused_ = meta.paused;
  // Waiters are released only now, so the frame they read next shows their command.
  const bool finished = !to_finish_.empty();
  FinishCommandsLocked();
  if (!may_coalesce || finished || meta.paused || Clock::now() - last_ring_ >= kRingCoalesce) {
    RingDoorbellsLocked();
  } else {
    unrung_ = true;
  }
}

void PhysicsEngine::HandleErrorLocked(const std::exception& e) {
  // An error thrown out of MuJoCo leaves its stack pointer where it was; nothing of ours is on
  // the mjData stack between iterations, so it is safe to release it all.
  data_->pstack = 0;
  RemoveOneShotForcesLocked(/*all=*/true);  // a step that threw keeps no one-shot force
  paused_.store(true, std::memory_order_release);
  error_latched_.store(true, std::memory_order_release);
  if (step_budget_ > 0) {  // the step window ends here, failed
    step_budget_ = 0;
    to_finish_.emplace_back(step_seq_, std::string("step: ") + e.what());
  }
  PublishFrameLocked();
  EngineEvent ev;
  ev.kind = EngineEventKind::kError;
  ev.sim_time = data_->time;
  ev.message = std::string("physics loop paused after an error: ") + e.what();
  if (log_events_) spdlog::error("{}", ev.message);
  QueueEvent(std::move(ev));
}

void PhysicsEngine::Loop() {
  bool window_ended = false;  // a lockstep window ended in the last iteration
  SpinWait spin;              // for the next lockstep request (gives up under CPU contention)
  auto next = Clock::now();
  auto window_start = next;
  {
    std::lock_guard<std::mutex> lock(step_mutex_);
    sim_advanced_ = 0;
    window_steps_ = 0;
  }
  while (!stop_.load(std::memory_order_acquire)) {
    const bool paused_now = paused();
    bool stepping = false;  // a lockstep window is under way (or commands wait behind one)
    {
      std::lock_guard<std::mutex> lock(step_mutex_);
      try {
        if (error_latched_.load(std::memory_order_acquire) && paused()) {
          // Commands still work; callbacks stay quiet; a step window cannot run.
          bool changed = ApplyPendingLocked();
          if (step_budget_ > 0) {
            step_budget_ = 0;
            to_finish_.emplace_back(step_seq_,
                                    "step: the simulation is paused after an error; unpause it");
            changed = true;
          }
          if (changed || published_paused_ != paused()) PublishFrameLocked();
        } else {
          IterateLocked(/*force_step=*/false, /*from_loop=*/true);
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
      stepping = step_budget_ > 0 || !backlog_.empty();
      // A frame published without a ring is announced before the loop could wait.
      if (unrung_ && !(as_fast_.load(std::memory_order_relaxed) && !paused())) {
        RingDoorbellsLocked();
      }
      window_ended = window_ended_;
      window_ended_ = false;
    }
    if (stepping || (as_fast_.load(std::memory_order_relaxed) && !paused_now)) {
      next = Clock::now();  // lockstep windows and as-fast-as-possible run without pacing
      continue;
    }
    if (paused_now) {
      // Lockstep: the next request usually follows within a round trip of the last window, so
      // wait for it briefly without sleeping (a futex wake-up costs more than the round trip).
      if (window_ended) {
        spin.Spin(kLockstepSpin, [&] {
          return commands_.pending() || !paused() || stop_.load(std::memory_order_relaxed);
        });
        if (commands_.pending() || !paused()) continue;
      }
      // Paused: sleep until a command arrives (lockstep requests wake the loop at once).
      std::unique_lock<std::mutex> lock(wake_mutex_);
      wake_cv_.wait_for(lock, kMaxSleep, [&] {
        return commands_.pending() || !paused() || stop_.load(std::memory_order_relaxed);
      });
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
