#pragma once
// InProcessBatch: a batch of N environments of a scene run inside the calling program's own
// process (EnvPool's way), with no server, socket or shared memory between the learner and the
// physics. It is `urlab run SCENE --envs N` without the network: the same session, the same
// world::BatchSubsystem (environment 0 is the engine's own simulation), the same resets, seeds,
// next-step auto-reset, episode limit, latency and randomisation, so environment i with seed s
// runs the same episode here as in a batched server. A step runs on the caller's thread and
// K-1 stepping workers (BatchSubsystem::StepHere); nothing else runs meanwhile. Every
// environment runs the scene's controllers: under a PD, keyframe or gait controller the actions
// are joint targets (action_low/high their ranges), as a client of `urlab run SCENE` sends them.
//
// The C interface over it (urlab/embed/urlab_batch.h, liburlab_batch.so) is what the Python
// client loads (urlab_client.inproc, UrlabVectorEnv.in_process).
//
// Threading contract
// - One owner thread at a time calls everything (construction, Step, Reset, destruction); the
//   C interface serialises its callers with a lock of its own.
// - Several InProcessBatch objects may live in one process (a training and an evaluation
//   batch), each with its own session, threads and engine; each has its own owner thread rule.
// - Step's and Reset's result stays valid until the next Step, Reset or the destructor.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "urlab/world/batch_subsystem.h"

namespace urlab::embed {

struct InProcessOptions {
  int envs = 1;
  int threads = 0;                    // stepping threads; 0: the machine's cores (at most envs)
  bool auto_reset = true;             // gymnasium's next-step autoreset, done here
  int max_episode_steps = 0;          // physics steps; 0: an episode ends only by divergence
  double reset_noise = 0;             // uniform noise at each reset (as --reset-noise)
  std::optional<std::uint64_t> seed;  // environment i starts with seed + i (none: the scene's)
  bool raw_actions = false;  // the actions are the controls; the scene's controllers stay off
};

class InProcessBatch {
 public:
  // Loads and compiles `scene` (a scene file or an MJCF model) and starts playing it paused.
  // Throws InputError / CompileError naming the file and line, Error for bad options.
  InProcessBatch(const std::string& scene, const InProcessOptions& options);
  ~InProcessBatch();
  InProcessBatch(const InProcessBatch&) = delete;
  InProcessBatch& operator=(const InProcessBatch&) = delete;

  int envs() const;
  int threads() const;
  int action_size() const;
  int observation_size() const;  // qpos, qvel, sensordata of the whole model
  int nq() const;
  int nv() const;
  int nsensordata() const;
  double timestep() const;
  // Each action's range, in actuator order: its controller's target range (the joint's range
  // under a PD), else the actuator's ctrlrange; -inf / +inf when it has none.
  const std::vector<double>& action_low() const;
  const std::vector<double>& action_high() const;
  std::vector<std::string> actuator_names() const;

  // One batch step of `n_steps` physics steps, the actions (envs x action_size, finite) held;
  // `reset` (empty, or one flag per environment): those reset instead of stepping. Throws
  // Error naming the field for arrays of the wrong size or a value that is not finite (nothing
  // is stepped then), or when the step could not complete.
  const world::BatchResult& Step(std::span<const double> actions,
                                 std::span<const std::uint8_t> reset = {}, int n_steps = 1);
  // Resets `envs` (empty: all), environment envs[k] from seeds[k] when it has one (seeds empty,
  // or one per entry). The result's rows are every environment's current observation.
  const world::BatchResult& Reset(std::span<const int> envs = {},
                                  std::span<const std::optional<std::uint64_t>> seeds = {});
  void SetAutoReset(bool on);

  // For MuJoCo's own tools (its Python bindings: urlab_client's model / data(i)). void pointers
  // keep this header free of MuJoCo's; both read the environment while nothing steps it.
  // - CopyModel: a copy (mj_copyModel) of environment `env`'s model (its own when the scene
  //   randomises, else the one they share), an mjModel* the caller owns (mj_deleteModel).
  // - CopyData: environment `env`'s whole mjData (state, what its last step computed,
  //   contacts; mj_copyData) into `data`, an mjData* made for a model of the same sizes (from
  //   CopyModel's copy). Throws Error for a bad index, or an mjData of other sizes.
  void* CopyModel(int env);
  void CopyData(int env, void* data);

 private:
  struct Playing;
  std::unique_ptr<Playing> playing_;
  std::shared_ptr<world::BatchStepJob> step_job_;
  std::shared_ptr<world::BatchResetJob> reset_job_;
  std::uint64_t steps_since_tick_ = 0;
};

}  // namespace urlab::embed
