#pragma once
// PhysicsEngine: owns one compiled mjModel and its mjData (in a StepCore, step_core.h) and
// steps them on a dedicated physics thread, paced on an injectable clock (core/clock.h).
//
// Threading contract
// - The physics thread (started by Start) owns mjModel/mjData while it runs. Each loop iteration
//   takes the step mutex once and, in this order: applies every queued command in submission
//   order (resets, restores, state writes, mocap poses, one-shot forces, options, pause; see
//   commands.h) and tells the command listeners, runs the pre-step callbacks, runs the
//   apply-controls hook, steps (unless paused: the custom step handler if set, else mj_step),
//   removes the one-shot forces, checks for divergence, runs the post-step callbacks, fires the
//   OnPostStep listeners (only when a step happened) and publishes a state frame to every
//   subscriber (after a step, after commands, and when the pause state changed): one
//   StepCore::Advance. It then releases the mutex and waits for the next deadline on its clock
//   (pacing); the real-time factor and step rate are measured on the same clock.
// - Callbacks, command listeners, the controls hook and the custom step handler run on the
//   physics thread (or on the StepSync caller's thread) with the step mutex held; they may read
//   and write mjData freely. From inside a callback, Submit and its wrappers and SetPaused are
//   allowed (queued for the next iteration); registration, Snapshot, WithLockedData, StepSync,
//   WaitForCommand, Start and Stop throw Error (they would deadlock).
// - Any thread: Submit and its wrappers (Reset*, Restore, ...), WaitForCommand, SetPaused,
//   Snapshot, the pacing setters, the measurement getters (atomics) and WithLockedData; StepSync
//   while the loop is paused (a lockstep server steps short windows on its own thread). Commands
//   are applied by the physics thread at its next iteration when it runs, immediately (under the
//   mutex, on the caller's thread) when it does not.
// - CopyModel and WithLockedData: any thread, not from inside a callback.
// - Main thread: Start, Stop, the destructor, callback and listener registration, state
//   subscriptions (before Start), and event delivery (PollEvents/DrainEvents). Reset
//   notifications, divergence and error reports are queued by the physics thread and only
//   delivered there.
// - State readers (any number, each on its own thread): their StateSubscription / StateRing
//   (state_frame.h); they never block the physics thread and never see live mjData. A reader
//   that sleeps in poll adds a Doorbell (core/doorbell.h) before Start: the physics thread rings
//   it after each published frame, once that frame's commands are finished.
// - A MuJoCo error (urlab::MujocoError from the installed handler) or any exception escaping a
//   callback is caught, reported as an kError event and pauses the loop; the process continues.
#include <mujoco/mujoco.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "urlab/core/clock.h"
#include "urlab/core/doorbell.h"
#include "urlab/physics/commands.h"
#include "urlab/physics/model.h"
#include "urlab/physics/state.h"
#include "urlab/physics/state_frame.h"
#include "urlab/physics/step_core.h"

namespace urlab::physics {

class PhysicsEngine {
 public:
  // A hook run with the step mutex held. The model is const: change it via WithLockedData.
  using StepCallback = physics::StepCallback;
  // Told on the physics thread (step mutex held) after each command was applied.
  using CommandListener = StepCore::CommandListener;
  // Maps a full element name (e.g. "g1_left_knee") to the articulation owning it ("g1").
  using ArticulationResolver = StepCore::ArticulationResolver;
  using EventListener = std::function<void(const EngineEvent&)>;
  using CallbackId = std::uint64_t;

  struct Options {
    double target_interval = 0;  // wall seconds per step at 100 % speed; 0: model timestep
    int speed_percent = 100;     // 5..100
    bool as_fast_as_possible = false;
    double resync_threshold = 0.05;  // seconds behind schedule before the schedule is reset
    bool reset_on_divergence = false;
    double measure_window = 0.25;  // wall seconds over which RTF and step rate are averaged
    // Log divergence and errors from the physics thread as they happen. An owner that logs the
    // events it drains (the Manager) turns this off so each is logged once.
    bool log_events = true;
    // Pacing, the measurements and the divergence log's rate limit run on this clock (it must
    // outlive the engine); null: RealClock(). Tests inject a ManualClock.
    Clock* clock = nullptr;
  };

  // Takes ownership of a compiled model with its extensions (model.h) and allocates its data
  // (mj_forward applied). Main thread.
  explicit PhysicsEngine(Model model);
  PhysicsEngine(Model model, Options options);
  ~PhysicsEngine();  // Stops the thread.
  PhysicsEngine(const PhysicsEngine&) = delete;
  PhysicsEngine& operator=(const PhysicsEngine&) = delete;

  // The model. Sizes, names and addresses never change; `opt` changes on the physics thread
  // (SetOptions commands) and other values too (ReplaceModel commands), so while the loop runs
  // read those under WithLockedData, or use timestep(). Any thread.
  const mjModel* model() const { return core_.model(); }
  // The model with its extensions (model.h): the same contract as model(); copy it with
  // CopyModel, or with owned_model().Copy() inside WithLockedData.
  const Model& owned_model() const { return core_.owned_model(); }
  // A copy of the model with its extensions and the options in effect now, taken with the step
  // mutex held. Any thread except from inside a step callback.
  Model CopyModel();
  // The model's current timestep (follows SetOptions). Any thread.
  double timestep() const { return core_.timestep(); }
  // Bumped by every applied ReplaceModel command (commands.h): a copy of the model taken before
  // is stale (sizes and names still match). Any thread.
  std::uint64_t model_generation() const { return core_.model_generation(); }

  // Runs `fn` with the step mutex held (blocks for at most one iteration). Any thread except from
  // inside a step callback.
  void WithLockedData(const std::function<void(mjModel*, mjData*)>& fn);

  // ---- Lifecycle (main thread) ----
  // Starts the physics thread. Throws Error if already running.
  void Start();
  // Asks the thread to stop and joins it. No-op when not running.
  void Stop();
  bool running() const { return running_.load(std::memory_order_acquire); }

  // ---- Hooks (main thread; not from inside a callback) ----
  CallbackId AddPreStepCallback(StepCallback fn);
  CallbackId AddPostStepCallback(StepCallback fn);
  // Fired after the post-step callbacks, only on iterations that stepped (replay records here).
  CallbackId AddOnPostStep(StepCallback fn);
  // Removes a callback added by any of the three functions above; false if unknown.
  bool RemoveCallback(CallbackId id);
  // The control layer's hook writing d->ctrl before each step (not on paused iterations that do
  // not step); empty function clears it.
  void SetApplyControlsHook(StepCallback fn);
  // The groups of command frames the apply-controls hook reports (one per controlled
  // articulation). Main thread, before subscriptions are made (their frames are sized for it).
  void SetCommandLayout(std::vector<CommandGroupLayout> layout);
  const std::vector<CommandGroupLayout>& command_layout() const { return core_.command_layout(); }
  // Physics thread, inside the apply-controls hook: where the hook writes the command frames it
  // applied; the frames published after the step carry them.
  AppliedCommands& applied_commands() { return core_.applied_commands(); }
  // Replaces mj_step while set (replay playback); empty function clears it.
  void SetCustomStepHandler(StepCallback fn);
  // Names the articulation in divergence reports.
  void SetArticulationResolver(ArticulationResolver fn);
  // Called after every applied command (a recorder marks resets and restores here). Removed with
  // RemoveCallback.
  CallbackId AddCommandListener(CommandListener fn);

  // ---- State readers (main thread, before Start or after Stop) ----
  // The newest frame for one reader thread.
  // `observed`: the state as an observer sees it, through SetObservationDelay's delay (the
  // network's topics and replies); otherwise the true state (recorder, viewer).
  std::shared_ptr<StateSubscription> SubscribeState(std::string name, bool observed = false);
  // Every frame, in order, through a ring of `capacity` frames (full: dropped and counted).
  std::shared_ptr<StateRing> SubscribeEveryStep(std::string name, std::size_t capacity,
                                                bool observed = false);
  // The observation delay of observed subscriptions (physics/observation_delay.h). Main thread,
  // before Start; configure it later under WithLockedData.
  void SetObservationDelay(std::shared_ptr<ObservationDelay> delay);
  // Drops a subscription made above; false when unknown.
  bool Unsubscribe(const void* subscription);
  // Rung on the physics thread after a published frame, once the commands that frame shows are
  // finished (a reader thread sleeping in poll wakes for new state and command results). Every
  // frame rings, except while running as fast as possible, where frames with nothing else due
  // ring at most every 50 µs and the last one always rings before the loop waits or pauses.
  void AddDoorbell(std::shared_ptr<Doorbell> doorbell);

  // ---- Commands (any thread) ----
  // Queues `command` (applied in submission order at the top of the next iteration; at once when
  // the loop does not run) and returns its sequence number. Throws Error / StateError at once
  // for a command that cannot apply to this model (bad id, wrong size, non-finite value).
  std::uint64_t Submit(Command command);
  // Waits until command `seq` took effect (or failed). Not from inside a step callback.
  CommandResult WaitForCommand(std::uint64_t seq, std::chrono::steady_clock::duration timeout);
  // Newest command applied (every older one is applied too).
  std::uint64_t last_applied_command() const { return core_.commands().last_applied(); }
  // Step commands with a sequence number up to `seq` that have not finished stop: a queued one
  // never runs, a running one stops after its current iteration. Each finishes failed with an
  // error starting kStepCancelled; commands of other kinds are untouched (and no longer wait
  // behind them). A lockstep server cancels queued work this way.
  void CancelStepsThrough(std::uint64_t seq);
  // Wrappers of Submit. mj_resetData + mj_forward.
  std::uint64_t Reset();
  // mj_resetDataKeyframe + mj_forward. Throws Error for a bad key id / unknown name.
  std::uint64_t ResetToKeyframe(int key);
  std::uint64_t ResetToKeyframe(const std::string& name);
  // Runs `fn` (on the physics thread, mutex held) then mj_forward; used for per-articulation
  // resets that must not touch the rest of the scene. `label` appears in the reset event.
  std::uint64_t ResetWith(StepCallback fn, std::string label);
  // Restores `state` then mj_forward. Throws StateError at once when it does not fit the model.
  std::uint64_t Restore(PhysicsState state);
  // Captures the full state (blocks for at most one iteration).
  PhysicsState Snapshot();

  // ---- Pause (any thread) ----
  // Immediate (an atomic; use Submit(cmd::SetPaused) to pause in order with other commands).
  // Unpausing also clears the error latch (after an error the paused loop runs no callbacks,
  // only commands, until it is unpaused).
  void SetPaused(bool paused);
  void TogglePause();
  bool paused() const { return core_.paused(); }
  // Runs `n` full iterations on the caller's thread, stepping even when paused. Only while the
  // loop is paused or not started (throws Error otherwise). A MuJoCo error is reported as an
  // event, pauses the loop and is rethrown.
  void StepSync(int n = 1);

  // ---- Pacing (any thread) ----
  void SetSpeedPercent(int percent);  // clamped to 5..100
  int speed_percent() const { return speed_percent_.load(std::memory_order_relaxed); }
  void SetAsFastAsPossible(bool on) { as_fast_.store(on, std::memory_order_relaxed); }
  bool as_fast_as_possible() const { return as_fast_.load(std::memory_order_relaxed); }
  // Wall seconds per step at 100 %; <= 0 follows the model timestep (also when it changes).
  void SetTargetInterval(double seconds);
  double target_interval() const {
    return follow_timestep_.load(std::memory_order_relaxed)
               ? timestep()
               : target_interval_.load(std::memory_order_relaxed);
  }
  void SetResetOnDivergence(bool on) { core_.SetResetOnDivergence(on); }

  // ---- Measurements (any thread) ----
  // Simulated seconds per wall second over the last measurement window (0 while paused).
  double real_time_factor() const { return rtf_.load(std::memory_order_relaxed); }
  // Steps per wall second over the last measurement window.
  double step_rate() const { return step_rate_.load(std::memory_order_relaxed); }
  // Physics steps taken (loop and StepSync).
  std::uint64_t step_count() const { return core_.step_count(); }

  // ---- Events (main thread) ----
  // Returns and clears the queued events without dispatching them.
  std::vector<EngineEvent> DrainEvents();
  // Drains the queue and calls every listener for each event; returns the number of events.
  int PollEvents();
  CallbackId AddEventListener(EventListener fn);
  // Events lost because the queue overflowed (it keeps the newest kMaxQueuedEvents).
  std::uint64_t dropped_events() const { return dropped_events_.load(std::memory_order_relaxed); }
  static constexpr std::size_t kMaxQueuedEvents = 1024;

 private:
  void Loop();
  // One iteration of the core, step mutex held by the caller; rings the doorbells for the frame
  // it published. `from_loop`: the physics thread's own loop running as fast as possible, which
  // may coalesce rings (see AddDoorbell). Throws what the core throws.
  StepCore::Iteration IterateLocked(StepCore::AdvanceOptions options, bool from_loop = false);
  // After an iteration threw: the core's error latch, then the doorbells.
  void FailLocked(const std::exception& e);
  void AfterPublishLocked(const StepCore::Iteration& it, bool may_coalesce);
  void RingDoorbellsLocked();
  void OnEvent(EngineEvent event);  // the core's event sink (physics thread)
  void QueueEvent(EngineEvent event);
  void ThrowIfOnPhysicsThread(const char* what) const;

  StepCore core_;
  Clock* clock_;

  // Serialises every access to the core once the engine is constructed.
  std::mutex step_mutex_;
  std::vector<std::shared_ptr<Doorbell>> doorbells_;
  std::chrono::steady_clock::time_point last_ring_{};  // mutex held: last doorbell ring
  bool unrung_ = false;                      // mutex held: a frame was published without a ring
  Clock::time_point last_divergence_log_{};  // mutex held
  std::mutex wake_mutex_;                    // with wake_cv_: a paused loop waits for commands
  std::condition_variable wake_cv_;

  // Events for the main thread.
  std::mutex events_mutex_;
  std::deque<EngineEvent> events_;
  std::vector<std::pair<CallbackId, EventListener>> listeners_;
  std::atomic<std::uint64_t> dropped_events_{0};
  CallbackId next_listener_id_ = 1;

  // Flags and pacing parameters.
  std::atomic<bool> stop_{false};
  std::atomic<bool> running_{false};
  std::atomic<int> speed_percent_{100};
  std::atomic<bool> as_fast_{false};
  std::atomic<double> target_interval_{0};
  std::atomic<bool> follow_timestep_{true};  // the target interval is the model timestep
  bool log_events_ = true;                   // see Options::log_events; set at construction
  double resync_threshold_ = 0.05;
  double measure_window_ = 0.25;

  // Measurements.
  std::atomic<double> rtf_{0};
  std::atomic<double> step_rate_{0};

  std::thread thread_;
};

}  // namespace urlab::physics
