#include "urlab/physics/step_core.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "physics/command_kinds.h"
#include "urlab/core/error.h"

namespace urlab::physics {

namespace {

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

int FirstBad(const mjtNum* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return i;
  }
  return -1;
}

}  // namespace

StepCore::StepCore(Model model) : StepCore(std::move(model), Options{}) {}

StepCore::StepCore(Model model, Options options)
    : StepCore(std::make_shared<Model>(std::move(model)), options) {}

StepCore::StepCore(std::shared_ptr<Model> shared, Options options)
    : model_(shared && *shared ? std::move(shared)
                               : throw Error("StepCore needs a compiled model")),
      log_command_failures_(options.log_command_failures),
      publisher_(model_->get()) {
  data_ = MakeData(model_->get());
  mj_forward(model_->get(), data_.get());
  reset_on_divergence_.store(options.reset_on_divergence);
  timestep_.store(model()->opt.timestep);
  qpos_joint_.assign(static_cast<std::size_t>(model()->nq), -1);
  for (int j = 0; j < model()->njnt; ++j) {
    const int next = j + 1 < model()->njnt ? model()->jnt_qposadr[j + 1] : model()->nq;
    for (int i = model()->jnt_qposadr[j]; i < next; ++i) {
      qpos_joint_[static_cast<std::size_t>(i)] = j;
    }
  }
}

// ---- Hooks

StepCore::CallbackId StepCore::AddHook(HookKind kind, StepCallback fn) {
  if (!fn) throw Error("StepCore: empty callback");
  auto& hooks = kind == HookKind::kPreStep    ? pre_step_
                : kind == HookKind::kPostStep ? post_step_
                                              : on_post_step_;
  const CallbackId id = next_id_++;
  hooks.push_back({id, std::move(fn)});
  return id;
}

StepCore::CallbackId StepCore::AddCommandListener(CommandListener fn) {
  if (!fn) throw Error("StepCore: empty command listener");
  const CallbackId id = next_id_++;
  command_listeners_.emplace_back(id, std::move(fn));
  return id;
}

bool StepCore::RemoveCallback(CallbackId id) {
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

void StepCore::SetCommandLayout(std::vector<CommandGroupLayout> layout) {
  applied_commands_ = AppliedCommands::SizedFor(layout);
  publisher_.SetCommandLayout(layout);
  command_layout_ = std::move(layout);
}

// ---- Commands, pause

void StepCore::Validate(const Command& command) const { ValidateCommand(command, model_->get()); }

void StepCore::CancelStepsThrough(std::uint64_t seq) {
  std::uint64_t now = cancel_steps_through_.load(std::memory_order_relaxed);
  while (now < seq && !cancel_steps_through_.compare_exchange_weak(now, seq)) {
  }
}

void StepCore::SetPaused(bool paused) {
  if (!paused) error_latched_.store(false, std::memory_order_release);
  paused_.store(paused, std::memory_order_release);
}

void StepCore::TogglePause() {
  bool expected = paused_.load();
  while (!paused_.compare_exchange_weak(expected, !expected)) {
  }
  if (expected) error_latched_.store(false, std::memory_order_release);
}

void StepCore::Emit(EngineEvent event) {
  if (event_sink_) event_sink_(std::move(event));
}

bool StepCore::ApplyPendingCommands() {
  if (step_budget_ > 0) return false;  // a step command runs first; the rest waits behind it
  if (!commands_.pending() && backlog_.empty()) return false;
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
      step_budget_ = step->n;  // finished by Advance after its last iteration
      step_total_ = step->n;
      step_seq_ = e.seq;
      break;
    }
    AppliedCommand applied;
    applied.seq = e.seq;
    applied.name = CommandName(e.command);
    try {
      applied.discontinuity = ApplyCommand(e.command, *this);
    } catch (const std::exception& ex) {
      // The command did not take effect (or only partly: a custom reset that threw); the state
      // is recomputed so the loop goes on from something consistent.
      applied.error = std::string(applied.name) + ": " + ex.what();
      data_->pstack = 0;
      mj_forward(model_->get(), data_.get());
      if (log_command_failures_) spdlog::warn("physics: command failed: {}", applied.error);
    }
    if (applied.discontinuity) {
      pending_discontinuity_ |= applied.discontinuity;
      ++epoch_;
    }
    for (const auto& [id, fn] : command_listeners_) fn(applied, model_->get(), data_.get());
    to_finish_.emplace_back(e.seq, std::move(applied.error));
  }
  return any;
}

void StepCore::FinishCommands() {
  for (auto& [seq, error] : to_finish_) commands_.Finish(seq, std::move(error));
  to_finish_.clear();
}

StepCore::Iteration StepCore::ApplyPending() {
  Iteration it;
  if (ApplyPendingCommands()) Publish(&it);
  return it;
}

// ---- The iteration

StepCore::Iteration StepCore::Advance(AdvanceOptions options) {
  Iteration it;
  if (options.honour_error_latch && error_latched() && paused()) {
    // Commands still work; hooks stay quiet; a step window cannot run.
    bool changed = ApplyPendingCommands();
    if (step_budget_ > 0) {
      step_budget_ = 0;
      to_finish_.emplace_back(step_seq_,
                              "step: the simulation is paused after an error; unpause it");
      changed = true;
    }
    if (changed || published_paused_ != paused()) Publish(&it);
    return it;
  }
  const mjModel* m = model_->get();
  mjData* d = data_.get();
  bool applied = ApplyPendingCommands();
  if (step_budget_ > 0 && step_seq_ <= cancel_steps_through_.load(std::memory_order_acquire)) {
    // The running step command was cancelled: its window ends here, the commands behind it go on.
    to_finish_.emplace_back(step_seq_, std::string(kStepCancelled) + " after " +
                                           std::to_string(step_total_ - step_budget_) + " of " +
                                           std::to_string(step_total_) + " steps");
    step_budget_ = 0;
    window_ended_ = true;
    ApplyPendingCommands();
    applied = true;
  }
  for (const Hook& h : pre_step_) h.fn(m, d);
  const bool budgeted = step_budget_ > 0;
  const bool step = options.force_step || budgeted || !paused();
  // Controls are written for a step only: while paused d->ctrl keeps what a command wrote (a
  // puppet client's ctrl, a restored state's).
  if (apply_controls_ && step) apply_controls_(m, d);
  if (step) Step();
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
  it.stepped = step;
  if (step || applied || !to_finish_.empty() || published_paused_ != paused()) Publish(&it);
  it.window_ended = window_ended_;
  window_ended_ = false;
  return it;
}

void StepCore::Step() {
  const mjModel* m = model_->get();
  mjData* d = data_.get();
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
  RemoveOneShotForces(/*all=*/false);  // each acts for its number of steps only
  step_count_.fetch_add(1, std::memory_order_relaxed);
  if (d->time > time_before) sim_advanced_ += d->time - time_before;
  ++progress_steps_;
  CheckDivergence(time_before);
}

int StepCore::JointOfIndex(int index, bool is_qpos) const {
  if (is_qpos) {
    return index >= 0 && index < model()->nq ? qpos_joint_[static_cast<std::size_t>(index)] : -1;
  }
  return index >= 0 && index < model()->nv ? model()->dof_jntid[index] : -1;
}

void StepCore::CheckDivergence(double time_before) {
  const mjModel* m = model_->get();
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
  Emit(e);
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
    Emit({EngineEventKind::kReset, time_before, "reset after divergence"});
  }
}

void StepCore::RemoveOneShotForces(bool all) {
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

// ---- Publication

FrameMeta StepCore::CurrentMeta() const {
  FrameMeta meta;
  meta.step = step_count();
  meta.frame = frames_;
  meta.command_seq = commands_.last_applied();
  meta.epoch = epoch_;
  meta.paused = paused();
  return meta;
}

void StepCore::Publish(Iteration* it) {
  FrameMeta meta;
  meta.step = step_count();
  meta.frame = ++frames_;
  meta.command_seq = to_finish_.empty() ? commands_.last_applied() : to_finish_.back().first;
  meta.discontinuity = pending_discontinuity_;
  meta.epoch = epoch_;
  meta.paused = paused();
  meta.stepped = last_iteration_stepped_;
  meta.xfrc_applied =
      stepped_xfrc_valid_ && last_iteration_stepped_ ? stepped_xfrc_.data() : nullptr;
  meta.commands = applied_commands_.empty() ? nullptr : &applied_commands_;
  publisher_.Publish(model_->get(), data_.get(), meta);
  stepped_xfrc_valid_ = false;
  last_iteration_stepped_ = false;
  pending_discontinuity_ = 0;
  published_paused_ = meta.paused;
  // Waiters are released only now, so the frame they read next shows their command.
  it->published = true;
  it->urgent = !to_finish_.empty() || meta.paused;
  FinishCommands();
}

StepCore::Iteration StepCore::Fail(const std::exception& e) {
  // An error thrown out of MuJoCo leaves its stack pointer where it was; nothing of ours is on
  // the mjData stack between iterations, so it is safe to release it all.
  data_->pstack = 0;
  RemoveOneShotForces(/*all=*/true);  // a step that threw keeps no one-shot force
  paused_.store(true, std::memory_order_release);
  error_latched_.store(true, std::memory_order_release);
  if (step_budget_ > 0) {  // the step window ends here, failed
    step_budget_ = 0;
    to_finish_.emplace_back(step_seq_, std::string("step: ") + e.what());
  }
  Iteration it;
  Publish(&it);
  EngineEvent ev;
  ev.kind = EngineEventKind::kError;
  ev.sim_time = data_->time;
  ev.message = std::string("physics loop paused after an error: ") + e.what();
  Emit(std::move(ev));
  return it;
}

StepCore::Progress StepCore::TakeProgress() {
  Progress p{sim_advanced_, progress_steps_};
  sim_advanced_ = 0;
  progress_steps_ = 0;
  return p;
}

}  // namespace urlab::physics
