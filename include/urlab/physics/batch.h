#pragma once
// Batch: N independent copies of one simulation in one process (one model, N mjData, each in a
// StepCore of its own), stepped in lockstep by K threads through StepCore::Advance. One Step
// takes N x nu actions and gives N x obs observations as packed arrays; each environment resets
// to a keyframe (or the model's default state) with noise drawn from its own seed, and may reset
// itself when its episode ends (auto-reset).
//
// With BatchOptions::randomize every environment has a model of its own, drawn at each of its
// resets; model() is then the copy they were made from (sizes and options are the same in all).
//
// Packed layouts (row-major, environment after environment, doubles):
// - actions: N x nu, in actuator order (written to ctrl before the environment's step; with a
//   control law (BatchOptions::control) they are its targets, and the law writes ctrl);
// - observations: N x observation_size(), each row qpos (nq), qvel (nv), sensordata
//   (nsensordata) as they are after the step (after the reset when it auto-reset), as observed
//   through the environment's observation latency when it has one (BatchOptions::latency);
// - done: N bytes, 1 when the environment's episode ended in this step (divergence, or
//   max_episode_steps reached).
//
// Threading contract
// - One owner calls everything below: one thread, or threads taking turns under a lock of the
//   caller's (a running engine's step mutex), never two at once. During Step the owner and K-1
//   persistent workers (a WorkerPool: no thread is created per step) advance the environments,
//   each claiming the next one of its own contiguous share first, then of the others' (an
//   environment keeps its thread from step to step while the threads keep pace; a preempted
//   thread holds back only the one it steps); no environment is touched by two threads in a
//   step, and the model is only read.
//   Which thread steps an environment changes none of its bits.
// - env(i) gives the environment's StepCore for its owner's use between steps (e.g. a state
//   subscription on environment 0 made before stepping starts); never during Step.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <vector>

#include "urlab/physics/env_latency.h"
#include "urlab/physics/model.h"
#include "urlab/physics/step_core.h"

namespace urlab {
class WorkerPool;
}

namespace urlab::physics {

// What turns an environment's actions into its controls when they are not the controls
// themselves (world: the scene's controllers, one set per environment, so a PD scene takes joint
// targets). Apply runs before each step of its environment, on the thread stepping it: d->ctrl
// holds the actions (after any control latency), in actuator order, and Apply writes the
// controls over them. Restart: the environment was reset (a law with a clock or memory starts
// afresh at the next Apply). Threading: one environment's law is called by one thread at a time.
class ControlLaw {
 public:
  virtual ~ControlLaw() = default;
  virtual void Apply(const mjModel* m, mjData* d) = 0;
  virtual void Restart() {}
};

struct BatchOptions {
  int envs = 1;
  int threads = 0;  // 0: the machine's cores; at most envs
  // Reset an environment as soon as its episode ended (its observation then shows the new
  // episode's first state).
  bool auto_reset = false;
  int max_episode_steps = 0;  // 0: an episode ends only when the simulation diverges
  int keyframe = -1;          // the reset state's keyframe; -1: the model's default state
  // At each reset, uniform noise in [-reset_noise, reset_noise] on hinge and slide positions,
  // free-joint positions and every velocity, drawn from the environment's generator.
  double reset_noise = 0;
  std::uint64_t seed = 0;  // environment i starts with seed + i
  // The reset state before the noise (null: `keyframe`, or the model's default state), e.g. a
  // session's initial state (every articulation in its initial keyframe). Called on the thread
  // that resets.
  std::function<void(const mjModel*, mjData*)> reset_state;
  // Emulated latency (physics/env_latency.h): environment `env`'s groups, seeds resolved (null
  // or empty groups: none). Asked once per environment when the batch is made; its control
  // lines delay the actions on their way to ctrl, its observation lines the observations.
  std::function<std::vector<EnvLatency::Group>(int env)> latency;
  // Domain randomisation: each environment gets a model of its own (a copy; one shared model
  // otherwise), and before each reset of environment `env` this draws into it and may add
  // position offsets (qpos address, offset) that the reset applies after the reset state and its
  // noise; `seed` is the reset's seed when it was given one (Reset). Called by the thread that
  // resets the environment (the owner; a worker for an auto-reset), never for one environment
  // on two threads at once.
  // The draw may also set the observation noise of the episode (EnvLatency::Noise).
  struct Draw {
    std::vector<std::pair<int, double>> qpos_offsets;
    std::vector<EnvLatency::Noise> noise;
  };
  std::function<void(int env, std::optional<std::uint64_t> seed, mjModel* m, Draw* draw)> randomize;
  // Environment `env`'s control law (null, or a null law: the actions are the controls). Asked
  // once per environment when the batch is made, before any reset (so `randomize` may reach the
  // law it made).
  std::function<std::unique_ptr<ControlLaw>(int env)> control;
};

// The state an environment resets to: options.reset_state (or the keyframe, or the default
// state), then the noise drawn from `rng`. The batch resets its environments with it; an
// environment kept outside the batch (a running engine's own) resets with it to the same state.
void ResetBatchState(const BatchOptions& options, std::mt19937_64& rng, const mjModel* m,
                     mjData* d);

class Batch {
 public:
  // Copies `model` (with its extensions) once; every environment shares the copy. Throws Error
  // for bad options (envs < 1, threads < 0, a keyframe the model lacks, negative noise).
  Batch(const Model& model, BatchOptions options);
  ~Batch();
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;

  int envs() const { return static_cast<int>(envs_.size()); }
  int threads() const;
  const mjModel* model() const { return model_->get(); }
  int action_size() const { return model()->nu; }
  int observation_size() const { return model()->nq + model()->nv + model()->nsensordata; }

  // Writes each environment's actions to its ctrl, advances every environment one iteration,
  // and writes the observations (and done flags when `done` is not empty). Throws Error for
  // arrays of the wrong size (nothing is stepped then), and after the step for an environment
  // whose iteration threw (it is reset when auto-reset is on, paused otherwise). `skip`
  // (empty, or one flag per environment): environments not stepped this time (their done is 0,
  // their observation the current one, their actions ignored). `iterations` > 1 advances each
  // environment that many iterations with the same actions (a frame skip) before the next one
  // is taken, so a thread keeps one environment's data in its caches for all of them and the
  // threads meet once per call, not once per iteration; done is then 1 when the episode ended in
  // any of them (an auto-reset environment goes on stepping from its reset), the observation the
  // last one's. Each environment's bits are those of `iterations` calls of one iteration.
  void Step(std::span<const double> actions, std::span<double> observations,
            std::span<std::uint8_t> done = {}, std::span<const std::uint8_t> skip = {},
            int iterations = 1);
  // Step in two halves, for an owner with work of its own to overlap (an engine stepping its
  // own environment): StepBegin checks the arrays and starts the workers on the environments;
  // StepEnd steps with them on the caller until none is left and throws like Step. The arrays
  // must stay valid, and the batch untouched, until StepEnd; a StepBegin, Step or the destructor
  // after a StepBegin without its StepEnd finishes that step first (so the arrays must outlive
  // the batch, or Settle be called before they go).
  void StepBegin(std::span<const double> actions, std::span<double> observations,
                 std::span<std::uint8_t> done = {}, std::span<const std::uint8_t> skip = {},
                 int iterations = 1);
  void StepEnd();
  // Finishes a step begun and not ended (its owner's work between the halves threw), dropping
  // its errors: call before touching the batch again.
  void Settle();
  // Resets environment `env` (keyframe or default state, then the noise); a seed restarts its
  // generator first. Throws Error for a bad index.
  void Reset(int env, std::optional<std::uint64_t> seed = std::nullopt);
  // Resets every environment; environment i gets seed + i when a seed is given.
  void ResetAll(std::optional<std::uint64_t> seed = std::nullopt);
  // The current observations (layout as Step's).
  void Observe(std::span<double> observations) const;
  // One environment's observation (observation_size() values at `out`).
  void ObserveOne(int env, double* out) const;
  // True when environment `env` diverged (or its iteration threw) since its last reset.
  bool diverged(int env) const;
  // Copies `opt` into the model the environments share, or into each one's own (physics options
  // changed elsewhere, e.g. on the simulation these environments mirror); `keep_gravity`: each
  // model keeps its gravity (drawn per environment). Not during Step.
  void SetPhysicsOptions(const mjOption& opt, bool keep_gravity = false);
  // Environment `env`'s model (its own when randomising, else the shared one).
  const mjModel* model(int env) const;
  // Steps since environment `env` last reset.
  std::uint64_t episode_steps(int env) const;
  StepCore& env(int i);

 private:
  struct Env;
  void StepEnv(Env& e, const double* action, double* obs, std::uint8_t* done);
  void ResetEnv(Env& e, std::optional<std::uint64_t> seed = std::nullopt);
  void ObserveEnv(const Env& e, double* out) const;   // as observed (through its latency)
  void ObserveTrue(const Env& e, double* out) const;  // the state itself
  void RestartLatency(Env& e);                        // after a reset

  // The step under way between StepBegin and StepEnd (the workers read them).
  struct Pass {
    std::span<const double> actions;
    std::span<double> observations;
    std::span<std::uint8_t> done;
    std::span<const std::uint8_t> skip;
    int iterations = 1;
  };
  // Each part's own contiguous share of the environments (part k: [k n / K, (k + 1) n / K)),
  // claimed from its front by its part first and by the others once theirs are done.
  struct alignas(64) Share {
    std::atomic<std::size_t> next{0};
    std::size_t end = 0;
  };
  void StepPart(int part);

  BatchOptions options_;
  std::shared_ptr<Model> model_;
  std::vector<std::unique_ptr<Env>> envs_;
  Pass pass_;
  std::unique_ptr<Share[]> shares_;
  std::function<void(int)> part_;     // StepPart, for the pool
  std::unique_ptr<WorkerPool> pool_;  // last: its workers stop before the rest goes
};

}  // namespace urlab::physics
