#pragma once
// StepCore: everything one simulation needs to advance, and the one function that advances it by
// one iteration. No thread, no lock of its own, no clock: the engine's physics thread, StepSync,
// its lockstep windows, the replay's re-simulation and a batch of environments all call
// Advance(); pacing and measurement against wall time belong to the caller (core/clock.h).
//
// One iteration (Advance), in order: the queued commands in submission order up to a step window
// (each applied through its kind's entry in src/physics/command_kinds.cc, the command listeners
// told), the pre-step hooks, then, when this iteration steps (not paused, a step window, or
// forced): the apply-controls hook, the one-shot forces added to xfrc_applied, mj_step (or the
// custom step handler), the one-shot forces taken out again, the divergence check (optionally
// followed by a reset); then the post-step hooks, the on-post-step hooks (only when it stepped),
// the end of a step window, and a state frame published to every subscription (after a step,
// after commands, or when the pause state changed), after which the finished commands' waiters
// are released.
//
// Threading contract
// - One thread at a time calls everything below that is not marked "any thread"; the owner
//   serialises (PhysicsEngine under its step mutex; a batch gives each environment to one worker
//   per step). Hooks, listeners and the event sink run on that thread, inside Advance.
// - Any thread: commands() (the queue is its own hand-off), Validate, CancelStepsThrough,
//   SetPaused/TogglePause/paused/error_latched, SetResetOnDivergence, step_count, timestep,
//   model_generation.
#include <mujoco/mujoco.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "urlab/physics/commands.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state_frame.h"

namespace urlab::physics {

// What an EngineEvent reports.
enum class EngineEventKind {
  kReset,       // mjData was reset (full, keyframe, custom or after divergence)
  kRestored,    // a state was restored
  kDivergence,  // NaN/Inf or a MuJoCo instability warning after a step
  kError,       // a MuJoCo error or a callback exception; the loop paused itself
};

// A notification from the iteration, delivered by its owner (the engine: on the main thread).
struct EngineEvent {
  EngineEventKind kind = EngineEventKind::kReset;
  double sim_time = 0;       // simulation time when it happened (before any reset it caused)
  std::string message;       // human-readable summary
  int joint_id = -1;         // kDivergence: offending joint, -1 when unknown
  std::string joint_name;    // kDivergence: its full (prefixed) name, "" when unnamed/unknown
  std::string articulation;  // kDivergence: from the articulation resolver, "" when none
  bool auto_reset = false;   // kDivergence: the engine reset the simulation in response
};

// A command as the iteration applied it, for the command listeners.
struct AppliedCommand {
  std::uint64_t seq = 0;
  const char* name = "";            // CommandName
  std::uint32_t discontinuity = 0;  // Discontinuity flags it caused (0: none)
  std::string error;                // non-empty when it failed
};

// The error a step command finishes with when it was cancelled (CancelStepsThrough) instead of
// running all its iterations.
inline constexpr std::string_view kStepCancelled = "step: cancelled";
inline bool IsCancelledStep(std::string_view error) { return error.starts_with(kStepCancelled); }

class StepCore {
 public:
  using CallbackId = std::uint64_t;
  using CommandListener = std::function<void(const AppliedCommand&, const mjModel*, const mjData*)>;
  // Maps a full element name (e.g. "g1_left_knee") to the articulation owning it ("g1").
  using ArticulationResolver = std::function<std::string(std::string_view name)>;
  // Receives every event of the iteration (resets, restores, divergence, errors).
  using EventSink = std::function<void(EngineEvent)>;
  enum class HookKind { kPreStep, kPostStep, kOnPostStep };

  struct Options {
    bool reset_on_divergence = false;
    bool log_command_failures = true;  // a failed command is logged as a warning
  };

  // Takes the compiled model with its extensions and allocates its data (mj_forward applied).
  explicit StepCore(Model model);
  StepCore(Model model, Options options);
  // Shares `model` with other cores (a batch of environments: one model, one mjData each). The
  // cores may then advance on different threads at once; a SetOptions command changes the
  // model of all of them, so their owner does not submit one while any of them advances.
  StepCore(std::shared_ptr<Model> model, Options options);
  StepCore(const StepCore&) = delete;
  StepCore& operator=(const StepCore&) = delete;

  const mjModel* model() const { return model_->get(); }
  mjModel* mutable_model() { return model_->get(); }
  const Model& owned_model() const { return *model_; }
  mjData* data() { return data_.get(); }
  const mjData* data() const { return data_.get(); }
  // The model's current timestep (follows SetOptions commands). Any thread.
  double timestep() const { return timestep_.load(std::memory_order_relaxed); }
  // How many times a ReplaceModel command changed the model's values (a copy of the model kept
  // elsewhere, e.g. the viewer's, is stale when this moved on). Any thread.
  std::uint64_t model_generation() const {
    return model_generation_.load(std::memory_order_acquire);
  }

  // ---- Hooks (not from inside Advance) ----
  CallbackId AddHook(HookKind kind, StepCallback fn);
  CallbackId AddCommandListener(CommandListener fn);
  // Removes a hook or command listener; false when unknown.
  bool RemoveCallback(CallbackId id);
  void SetApplyControlsHook(StepCallback fn) { apply_controls_ = std::move(fn); }
  void SetCustomStepHandler(StepCallback fn) { custom_step_ = std::move(fn); }
  void SetArticulationResolver(ArticulationResolver fn) { resolver_ = std::move(fn); }
  void SetEventSink(EventSink fn) { event_sink_ = std::move(fn); }
  void SetCommandLayout(std::vector<CommandGroupLayout> layout);
  const std::vector<CommandGroupLayout>& command_layout() const { return command_layout_; }
  // Inside the apply-controls hook: where it writes the command frames it applied.
  AppliedCommands& applied_commands() { return applied_commands_; }

  // ---- Commands ----
  // Any thread: the queue other threads push to (Submit validates first).
  CommandQueue& commands() { return commands_; }
  const CommandQueue& commands() const { return commands_; }
  // Any thread: throws Error / StateError when `command` cannot apply to this model.
  void Validate(const Command& command) const;
  // Any thread: step commands up to `seq` stop (see PhysicsEngine::CancelStepsThrough).
  void CancelStepsThrough(std::uint64_t seq);
  // A step window runs, or commands taken from the queue wait behind one.
  bool stepping() const { return step_budget_ > 0 || !backlog_.empty(); }

  // ---- Pause and the error latch (any thread) ----
  // Unpausing also clears the error latch.
  void SetPaused(bool paused);
  void TogglePause();
  bool paused() const { return paused_.load(std::memory_order_acquire); }
  bool error_latched() const { return error_latched_.load(std::memory_order_acquire); }
  void SetResetOnDivergence(bool on) { reset_on_divergence_.store(on, std::memory_order_relaxed); }

  // ---- The iteration ----
  struct AdvanceOptions {
    bool force_step = false;  // step even while paused (StepSync, a batch)
    // While the error latch holds and the core is paused, only commands are applied (hooks stay
    // quiet) and a step window fails at once.
    bool honour_error_latch = true;
  };
  struct Iteration {
    bool stepped = false;       // mj_step (or the custom step) ran
    bool published = false;     // a state frame was published
    bool urgent = false;        // that frame finished commands or shows a pause: tell readers now
    bool window_ended = false;  // a step command's window ended in this iteration
  };
  // One iteration. Throws what applying the step or a hook throws (the caller then calls Fail).
  Iteration Advance(AdvanceOptions options);
  Iteration Advance() { return Advance(AdvanceOptions{}); }
  // Applies the queued commands (up to a step window) and publishes a frame when any was taken.
  Iteration ApplyPending();
  // After Advance threw: releases MuJoCo's stack, drops the one-shot forces, pauses and latches,
  // fails a running step window, publishes a frame and reports a kError event.
  Iteration Fail(const std::exception& e);

  // ---- Publication ----
  // Not from inside Advance. Subscriptions are made before the owner starts stepping.
  StatePublisher& publisher() { return publisher_; }
  // The metadata a frame of the current state carries (a new subscription's first frame).
  FrameMeta CurrentMeta() const;

  // ---- Measurement ----
  // Steps taken. Any thread.
  std::uint64_t step_count() const { return step_count_.load(std::memory_order_relaxed); }
  // Simulated seconds and steps since the last call.
  struct Progress {
    double sim_seconds = 0;
    std::uint64_t steps = 0;
  };
  Progress TakeProgress();

 private:
  friend struct CommandAccess;  // command_kinds.cc applies commands through it
  struct Hook {
    CallbackId id;
    StepCallback fn;
  };

  bool ApplyPendingCommands();
  void FinishCommands();
  void Step();
  void CheckDivergence(double time_before);
  void Publish(Iteration* it);
  void RemoveOneShotForces(bool all);
  void Emit(EngineEvent event);
  int JointOfIndex(int index, bool is_qpos) const;

  std::shared_ptr<Model> model_;
  DataPtr data_;
  std::vector<Hook> pre_step_, post_step_, on_post_step_;
  std::vector<std::pair<CallbackId, CommandListener>> command_listeners_;
  StepCallback apply_controls_;
  StepCallback custom_step_;
  ArticulationResolver resolver_;
  EventSink event_sink_;
  std::vector<CommandGroupLayout> command_layout_;
  AppliedCommands applied_commands_;
  CallbackId next_id_ = 1;
  bool log_command_failures_ = true;
  std::vector<int> qpos_joint_;  // qpos index -> joint id
  bool in_divergence_ = false;

  CommandQueue commands_;
  std::deque<CommandQueue::Entry> backlog_;                       // taken, not yet applied
  std::vector<std::pair<std::uint64_t, std::string>> to_finish_;  // applied, to release after
                                                                  // publishing
  int step_budget_ = 0;         // iterations left in a step command's window
  std::uint64_t step_seq_ = 0;  // that step command
  int step_total_ = 0;          // its n
  bool window_ended_ = false;   // the window ended in this iteration
  std::atomic<std::uint64_t> cancel_steps_through_{0};

  std::vector<cmd::ApplyForce> one_shot_;  // forces for the next step
  bool one_shot_added_ = false;            // one_shot_ is in xfrc_applied now
  // The xfrc_applied rows the one-shot forces changed, as they were before (put back exactly,
  // not by subtraction), and the whole xfrc_applied the last step used when it had one-shot
  // forces (the published frame reports it).
  std::vector<std::pair<int, std::array<mjtNum, 6>>> one_shot_saved_;
  std::vector<mjtNum> stepped_xfrc_;
  bool stepped_xfrc_valid_ = false;

  bool last_iteration_stepped_ = false;      // for the frame being published
  std::uint32_t pending_discontinuity_ = 0;  // since the last published frame
  std::uint64_t epoch_ = 0;                  // discontinuities so far
  std::uint64_t frames_ = 0;                 // frames published
  bool published_paused_ = false;            // pause state of the last frame

  std::atomic<bool> paused_{false};
  std::atomic<bool> error_latched_{false};
  std::atomic<bool> reset_on_divergence_{false};
  std::atomic<double> timestep_{0};
  std::atomic<std::uint64_t> model_generation_{0};
  std::atomic<std::uint64_t> step_count_{0};
  double sim_advanced_ = 0;
  std::uint64_t progress_steps_ = 0;

  StatePublisher publisher_;
};

}  // namespace urlab::physics
