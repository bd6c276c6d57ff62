#pragma once
// BatchSubsystem: N independent copies of the running scene (`urlab run --envs N`), stepped in
// lockstep. One environment (0, or options.engine_env: `--record-env I`) is the engine's own
// simulation, so the streaming topics, the viewer and the recorder follow it unchanged; the other
// N-1 live in a physics::Batch (one copy of the model, one mjData each, K threads) that only the
// iterating thread touches, in the same iteration as the engine's. Every environment resets to
// the session's initial state (each articulation in its initial keyframe) plus noise from its own
// generator (physics::ResetBatchState), so environment i with seed s runs the same episode as
// any environment of another run reset with seed s. Below, "environment 0" stands for the
// engine's environment; arrays on the wire are in environment order whichever it is.
//
// A batch step (SubmitStep) is, for the engine, one lockstep window: an Inspect command arms the
// job (the other environments' resets, the options environment 0 runs with), then a Step{n}
// command. While that window runs, the apply-controls hook writes environment 0's actions over
// what the session's controllers wrote, and a post-step hook
// steps the other environments once per iteration. When environment 0 resets in a batch step
// (gymnasium's next-step autoreset: the step after an episode ended resets that environment and
// ignores its action), its reset is a ResetCustom command (the recorder sees the discontinuity)
// and the other environments step inside an Inspect command instead of a window. StepHere runs
// the same window on the requesting thread (PhysicsEngine::StepSync) instead of the physics
// thread's.
//
// Actions are in actuator order, what a client of the running scene sends: every environment
// runs the scene's controllers of its own (EnvControls, built from the scene as the session
// builds its own), so under a PD, keyframe or gait controller an action is a joint target (the
// gait's twist stays detached: a PD on joint targets), under none the control itself.
// action_low/high are the targets' ranges. With options.raw_actions the actions are the controls
// and no controller runs (bounds: the ctrlranges).
//
// Episodes end (done) when an environment diverges (NaN/Inf, MuJoCo's instability warnings) or
// reaches max_episode_steps physics steps; with auto_reset the next batch step resets it.
//
// Threading contract
// - Main thread: construction, BeginPlay (hooks installed before the physics thread starts),
//   EndPlay (hooks removed).
// - One requesting thread (the step server's I/O thread): SubmitStep, StepHere, SubmitReset and
//   the getters; one batch request at a time (the next one after the previous job completed). A
//   job's outputs are written by the iterating thread before the command the requester waits for
//   finishes (PhysicsEngine::last_applied_command / WaitForCommand order them), or before
//   StepHere returns.
// - The iterating thread, always with the engine's step mutex held: the hooks, the command
//   functions and every environment's state. That is the physics thread, or the requesting
//   thread itself inside StepHere (PhysicsEngine::StepSync and WithLockedData take the mutex);
//   the batch's worker threads step environments 1..N-1 only inside an iteration, and in a
//   window's last iteration write their observation rows (others_obs_), which the iterating
//   thread reads after joining them (Batch::StepEnd).
// - Detached: the requesting thread's StepHere steps every environment, with the batch's workers
//   and the step mutex held; a reset's Inspect command touches them on the physics thread (or
//   the requester's, when the loop is not running) while the requester waits for it.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "urlab/physics/batch.h"
#include "urlab/physics/latency.h"
#include "urlab/world/randomize.h"
#include "urlab/world/subsystem.h"

namespace urlab::world {

class Randomizer;   // src/world/randomizer.h
class EnvControls;  // src/world/env_controls.h

struct BatchSubsystemOptions {
  int envs = 1;
  int threads = 0;            // 0: the machine's cores (at most envs)
  bool auto_reset = true;     // reset an ended episode at the next batch step (next-step)
  int max_episode_steps = 0;  // physics steps; 0: episodes end only by divergence
  double reset_noise = 0;     // uniform noise at each reset (physics::BatchOptions)
  std::uint64_t seed = 0;     // environment i starts with seed + i
  // The environment the engine itself runs (`urlab run --record-env I`): the streaming topics,
  // the viewer and the recorder follow it; the others live in the batch.
  int engine_env = 0;
  // No environment is the engine's: all N live in the batch and step on the requesting thread
  // and the batch's workers (StepHere always), the engine left paused and unmoved; for a front
  // end with no topics, viewer or recorder to follow one (the in-process batch). engine_env is
  // ignored, and the episodes are the same as with one.
  bool detached = false;
  // The actions are each actuator's control (ctrl) and the scene's controllers do not run in the
  // environments (`urlab run --raw-actions`): for learning on torques in a scene written with a
  // PD, and for benchmarks that compare the batch with a bare loop of raw controls.
  bool raw_actions = false;
};

// The outputs every batch job fills (one entry or row per environment).
struct BatchResult {
  std::vector<double> obs;                   // envs x observation_size: qpos, qvel, sensordata
  std::vector<std::uint8_t> done;            // the episode ended in this request
  std::vector<std::uint8_t> reset;           // the environment was reset in this request
  std::vector<double> time;                  // each environment's simulation time
  std::vector<std::uint32_t> episode_steps;  // physics steps since its last reset
  double seconds = 0;                        // wall time the iterating thread spent
  bool complete = false;
};

struct BatchStepJob {
  std::vector<double> actions;      // envs x action_size
  std::vector<std::uint8_t> reset;  // envs flags (empty: none): reset instead of stepping
  int n = 1;                        // physics steps (the actions held)
  BatchResult out;
};

struct BatchResetJob {
  std::vector<int> envs;                            // empty: every environment
  std::vector<std::optional<std::uint64_t>> seeds;  // per entry of envs (or per environment)
  BatchResult out;
};

class BatchSubsystem : public Subsystem {
 public:
  explicit BatchSubsystem(BatchSubsystemOptions options);
  ~BatchSubsystem() override;

  std::string_view name() const override { return "batch"; }
  void BeginPlay(Session& session) override;
  void EndPlay(Session& session) override;
  std::vector<StatusLine> Status() const override;

  // ---- Sizes (fixed once playing) ----
  int envs() const { return options_.envs; }
  int engine_env() const { return options_.engine_env; }  // -1 when detached
  bool detached() const { return options_.detached; }
  int threads() const;
  int action_size() const { return nu_; }
  int observation_size() const { return nq_ + nv_ + nsensordata_; }
  // The actions' bounds: each actuator's ctrlrange (-inf / +inf when it has none), in actuator
  // order.
  const std::vector<double>& action_low() const { return action_low_; }
  const std::vector<double>& action_high() const { return action_high_; }
  int nq() const { return nq_; }
  int nv() const { return nv_; }
  int nsensordata() const { return nsensordata_; }
  int max_episode_steps() const { return options_.max_episode_steps; }
  double reset_noise() const { return options_.reset_noise; }
  bool auto_reset() const { return auto_reset_.load(std::memory_order_relaxed); }
  void SetAutoReset(bool on) { auto_reset_.store(on, std::memory_order_relaxed); }
  // Environment steps taken (sum over environments) and the iterating thread's wall seconds on
  // batch jobs, since play began.
  std::uint64_t env_steps() const { return env_steps_.load(std::memory_order_relaxed); }
  double busy_seconds() const { return busy_seconds_.load(std::memory_order_relaxed); }

  // ---- Requests (the requesting thread) ----
  // Queues the commands of one batch step and returns the one to wait for; its steps (n when
  // it is a lockstep window the server may cancel, 0 otherwise) in *steps. Throws Error for
  // arrays of the wrong size, and when detached (StepHere steps every job then).
  std::uint64_t SubmitStep(std::shared_ptr<BatchStepJob> job, std::uint64_t* steps);
  // Runs one batch step on this thread (PhysicsEngine::StepSync: the requesting thread and the
  // batch's workers step, the physics thread stays asleep) and returns true with the job
  // complete; false, with nothing done, while the loop runs or when environment 0 resets in
  // this step (then SubmitStep). Throws Error like SubmitStep, or when the window stopped
  // part-way (a MuJoCo error: the job does not complete). Detached, it always steps here.
  bool StepHere(const std::shared_ptr<BatchStepJob>& job);
  // Queues the resets (environment 0's as a ResetCustom command) and returns the command to wait
  // for. Throws Error for a bad environment index.
  std::uint64_t SubmitReset(std::shared_ptr<BatchResetJob> job);
  // After the server cancelled a batch step's window (before or while it ran): a command that
  // drops the job it armed, so that no later iteration (a plain step) takes it for its own.
  void Disarm();
  // The episodes that ended in the last completed step (read by the requester after the job
  // completed; auto-reset resets them at the next step).
  void NoteCompleted(const BatchResult& out);
  // Runs `fn` with environment `env`'s model (its own when the scene randomises) and data, the
  // engine's step mutex held: nothing steps or resets them meanwhile. For reading them (the
  // in-process batch's copies for MuJoCo's Python bindings). Not from inside an engine callback;
  // not while a detached step runs. Throws Error for a bad index.
  void WithEnvironment(int env, const std::function<void(const mjModel*, const mjData*)>& fn);

 private:
  struct Job;
  void ApplyControls(const mjModel* m, mjData* d);
  void PostStep(const mjModel* m, mjData* d);
  void OnCommand(const physics::AppliedCommand& c);
  void ResetEnv0(const mjModel* m, mjData* d, std::optional<std::uint64_t> seed);
  void SyncOptions(const mjModel* m);
  void CheckStep(const BatchStepJob& job) const;  // throws Error for arrays of the wrong size
  void TakeResets(BatchStepJob& job);  // the job's reset flags (auto-reset adds the ended)
  // Arms `job` for the next window (the other environments' resets, the options); step mutex.
  void Arm(const std::shared_ptr<BatchStepJob>& job, const mjModel* m);
  // Detached: one batch step of every environment, here (the requesting thread's StepHere).
  void StepDetached(BatchStepJob& job);
  // Steps the other environments once (not those in `skip`), or-ing their done flags into
  // `done`; `begun`: ApplyControls started that step (Batch::StepBegin), this finishes it.
  void StepOthers(const std::vector<double>& actions, std::vector<std::uint8_t>& done,
                  const std::vector<std::uint8_t>& skip, bool begun = false);
  // Fills out's rows: environment 0 from `d`, the others from the batch.
  void Gather(const mjModel* m, const mjData* d, BatchResult& out);
  static bool Diverged(const mjModel* m, const mjData* d);
  // Emulated latency: environment `env`'s groups (seeds resolved); environment 0's lines.
  std::vector<physics::EnvLatency::Group> LatencyGroups(int env) const;
  void RestartEnv0Latency(const mjData* d);
  // Domain randomisation: environment `env`'s next draw into `m` (its own model; the engine's
  // for environment 0), its position offsets in *offsets.
  void Draw(int env, std::optional<std::uint64_t> seed, mjModel* m,
            physics::BatchOptions::Draw* draw);
  // Environment 0's observed row after a step (`stepped`), or its reset state as tick 0.
  void ObserveEnv0(const mjModel* m, const mjData* d, bool stepped);
  static void TrueRow(const mjModel* m, const mjData* d, double* row);
  // Environment e (not the engine's) is the batch's Other(e); the batch's j is environment
  // Wire(j).
  // (Detached, engine_env is -1: both are the identity.)
  int Other(int e) const { return e < options_.engine_env || detached() ? e : e - 1; }
  int Wire(int j) const { return j < options_.engine_env || detached() ? j : j + 1; }
  // The rows of `all` (one per environment, `width` values each) without the engine's: a view
  // on `all`, or on `scratch` filled with them.
  template <typename T>
  std::span<const T> OthersRows(const std::vector<T>& all, std::size_t width,
                                std::vector<T>* scratch) const;

  BatchSubsystemOptions options_;
  physics::BatchOptions batch_options_;  // the reset state, noise, max steps (all environments)
  Session* session_ = nullptr;
  std::unique_ptr<physics::Batch> others_;  // environments 1..N-1 (null when N == 1)
  int nu_ = 0, nq_ = 0, nv_ = 0, nsensordata_ = 0;
  std::vector<double> action_low_, action_high_;
  std::vector<std::uint64_t> callbacks_;
  // The scene's controllers, one set per environment (none when every articulation passes its
  // targets through): environment 0's here, the batch's own inside it; by environment, for the
  // randomisation's PD gains (each touched only by the thread resetting or stepping it).
  std::unique_ptr<EnvControls> env0_controls_;
  std::vector<EnvControls*> env_controls_;
  // The articulations with a latency: their actuators, observation row entries and settings.
  struct LatencyTemplate {
    std::size_t index = 0;  // the articulation's index (its seed stream)
    physics::ArticulationLatency latency;
    std::vector<int> observed, actuators;
  };
  std::vector<LatencyTemplate> latency_;
  std::vector<std::vector<int>> observed_;  // per articulation: its observation row entries
  // Domain randomisation (null: none): each environment's stream of draws, touched only by the
  // thread resetting it (the iterating thread; the main thread in BeginPlay).
  struct Stream {
    std::uint64_t base = 0;  // the run's seed + env, or the seed of its last seeded reset
    std::uint64_t n = 0;     // randomised resets drawn from base
  };
  std::shared_ptr<const Randomizer> randomizer_;
  RandomizeConfig randomize_;
  bool randomize_gravity_ = false;
  std::vector<Stream> draws_;
  std::uint64_t latency_seed_ = 0;
  double timestep_ = 0;
  std::atomic<bool> auto_reset_{true};
  std::atomic<std::uint64_t> env_steps_{0};
  std::atomic<double> busy_seconds_{0};

  // Requesting thread: the episodes that ended in the last completed step; the last job
  // SubmitStep armed through commands (for Disarm).
  std::vector<std::uint8_t> ended_;
  std::shared_ptr<BatchStepJob> submitted_;

  // The iterating thread only (step mutex held).
  std::mt19937_64 env0_rng_;
  physics::EnvLatency env0_latency_;
  std::vector<double> env0_observed_;      // environment 0's observed row (delayed observations)
  bool env0_restart_observation_ = false;  // reset since: its lines restart before the next use
  std::uint32_t env0_steps_ = 0;
  bool env0_diverged_ = false;
  std::shared_ptr<BatchStepJob> armed_;  // a window's job, armed by its Inspect command
  std::uint64_t window_ = 0;             // 1 once armed_'s window stepped (0: not started)
  int iterations_ = 0;                   // of armed_'s window so far
  std::vector<std::uint8_t> skip_, done_, iteration_done_;  // per other environment
  std::vector<double> others_actions_;                      // their actions (OthersRows)
  // Their observation rows, written by the stepping threads in a window's last iteration;
  // others_observed_: they hold the state Gather reports (false once anything else moved it).
  std::vector<double> others_obs_;
  bool others_observed_ = false;
  double started_ = 0;  // armed_'s start (steady seconds)
};

}  // namespace urlab::world
