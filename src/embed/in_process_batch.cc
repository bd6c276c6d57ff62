#include "urlab/embed/in_process_batch.h"

#include <mujoco/mujoco.h>

#include <chrono>
#include <cmath>

#include "ops/value_ranges.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/error.h"
#include "urlab/net/scene_settings.h"
#include "urlab/ops/batch.h"
#include "urlab/viewer/scene_settings.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene_file.h"

namespace urlab::embed {

namespace {

// Seeds are whole numbers a double holds exactly, as the step server takes them (ops' table).
void CheckSeed(std::uint64_t seed, const char* what) {
  const ops::ValueRange& r = ops::RangeOf("seed");
  if (static_cast<double>(seed) > r.max) {
    throw Error(std::string(what) + ": " + std::to_string(seed) + " is not " + ops::RangeText(r));
  }
}

// How long a reset (commands the paused physics thread applies) may take.
constexpr auto kCommandTimeout = std::chrono::seconds(60);
// Engine events (divergences, MuJoCo errors) reach the log through Manager::Tick: once every so
// many steps, and after each reset.
constexpr std::uint64_t kTickEvery = 64;

}  // namespace

struct InProcessBatch::Playing {
  world::Manager manager;
  world::BatchSubsystem* batch = nullptr;
  explicit Playing(const world::ManagerOptions& o) : manager(o) {}
};

InProcessBatch::InProcessBatch(const std::string& scene, const InProcessOptions& options) {
  // The options by their names here (the batch subsystem's own messages name urlab run's flags).
  if (options.envs < 1) {
    throw Error("envs must be at least 1 (got " + std::to_string(options.envs) + ")");
  }
  if (options.threads < 0) {
    throw Error("threads must be 0 (the cores) or more (got " + std::to_string(options.threads) +
                ")");
  }
  if (options.max_episode_steps < 0) throw Error("max_episode_steps must be 0 or more");
  if (!(options.reset_noise >= 0) || !std::isfinite(options.reset_noise)) {
    throw Error("reset_noise must be a finite number, 0 or more");
  }
  if (options.seed) CheckSeed(*options.seed, "seed");
  // The scene sections the `urlab` tool knows (a scene written for `urlab run` loads here as it
  // is; the network, cameras and viewer they configure do not run).
  viewer::RegisterSceneSections();
  camera::RegisterSceneSections();
  net::RegisterSceneSections();
  world::SceneConfig config = world::LoadSceneOrModel(scene);
  if (options.seed) config.seed = *options.seed;
  world::ManagerOptions manager_options;
  manager_options.start_paused = true;  // lockstep: it steps only when asked
  manager_options.as_fast_as_possible = true;
  playing_ = std::make_unique<Playing>(manager_options);
  world::BatchSubsystemOptions batch_options;
  batch_options.envs = options.envs;
  batch_options.threads = options.threads;
  batch_options.auto_reset = options.auto_reset;
  batch_options.max_episode_steps = options.max_episode_steps;
  batch_options.reset_noise = options.reset_noise;
  batch_options.seed = config.seed;  // environment i: the seed + i
  batch_options.detached = true;     // no topics, viewer or recorder follow an environment here
  batch_options.raw_actions = options.raw_actions;
  playing_->batch = &static_cast<world::BatchSubsystem&>(
      playing_->manager.AddSubsystem(std::make_unique<world::BatchSubsystem>(batch_options)));
  playing_->manager.BeginPlay(config);
  step_job_ = std::make_shared<world::BatchStepJob>();
  reset_job_ = std::make_shared<world::BatchResetJob>();
}

InProcessBatch::~InProcessBatch() = default;

int InProcessBatch::envs() const { return playing_->batch->envs(); }
int InProcessBatch::threads() const { return playing_->batch->threads(); }
int InProcessBatch::action_size() const { return playing_->batch->action_size(); }
int InProcessBatch::observation_size() const { return playing_->batch->observation_size(); }
int InProcessBatch::nq() const { return playing_->batch->nq(); }
int InProcessBatch::nv() const { return playing_->batch->nv(); }
int InProcessBatch::nsensordata() const { return playing_->batch->nsensordata(); }
const std::vector<double>& InProcessBatch::action_low() const {
  return playing_->batch->action_low();
}
const std::vector<double>& InProcessBatch::action_high() const {
  return playing_->batch->action_high();
}
double InProcessBatch::timestep() const { return playing_->manager.session().engine().timestep(); }

std::vector<std::string> InProcessBatch::actuator_names() const {
  const mjModel* m = playing_->manager.session().engine().model();
  std::vector<std::string> names;
  for (int i = 0; i < m->nu; ++i) {
    const char* name = mj_id2name(m, mjOBJ_ACTUATOR, i);
    names.emplace_back(name ? name : "");
  }
  return names;
}

void InProcessBatch::SetAutoReset(bool on) { playing_->batch->SetAutoReset(on); }

void* InProcessBatch::CopyModel(int env) {
  mjModel* copy = nullptr;
  playing_->batch->WithEnvironment(
      env, [&](const mjModel* m, const mjData*) { copy = mj_copyModel(nullptr, m); });
  if (!copy) throw Error("environment " + std::to_string(env) + ": could not copy its model");
  return copy;
}

void InProcessBatch::CopyData(int env, void* data) {
  if (!data) throw Error("data: no mjData given");
  mjData* dest = static_cast<mjData*>(data);
  playing_->batch->WithEnvironment(env, [&](const mjModel* m, const mjData* d) {
    // mj_copyData's own checks, here as an Error rather than MuJoCo's error callback.
    if (dest->nbuffer != d->nbuffer || dest->narena != d->narena) {
      throw Error("data: an mjData of other sizes than environment " + std::to_string(env) +
                  "'s (make it for the batch's model copy)");
    }
    mj_copyData(dest, m, d);
  });
}

const world::BatchResult& InProcessBatch::Step(std::span<const double> actions,
                                               std::span<const std::uint8_t> reset, int n_steps) {
  world::BatchSubsystem& b = *playing_->batch;
  // One job, reused: its arrays keep their capacity from step to step.
  world::BatchStepJob& job = *step_job_;
  job.actions.assign(actions.begin(), actions.end());
  job.reset.assign(reset.begin(), reset.end());
  // The step server's checks (ops::CheckBatchStep); BatchSubsystem::CheckStep refuses n_steps < 1.
  ops::CheckBatchStep(b, job.actions, job.reset);
  for (std::uint8_t& f : job.reset) f = f != 0;
  job.n = n_steps;
  job.out.complete = false;
  b.StepHere(step_job_);  // detached: always here, on this thread and the batch's workers
  if (!job.out.complete) throw Error("the batch step did not complete");
  b.NoteCompleted(job.out);
  steps_since_tick_ += static_cast<std::uint64_t>(n_steps);
  if (steps_since_tick_ >= kTickEvery) {
    steps_since_tick_ = 0;
    playing_->manager.Tick();
  }
  return job.out;
}

const world::BatchResult& InProcessBatch::Reset(
    std::span<const int> envs, std::span<const std::optional<std::uint64_t>> seeds) {
  for (const std::optional<std::uint64_t>& seed : seeds) {
    if (seed) CheckSeed(*seed, "seeds");
  }
  world::BatchSubsystem& b = *playing_->batch;
  world::BatchResetJob& job = *reset_job_;
  job.envs.assign(envs.begin(), envs.end());
  job.seeds.assign(seeds.begin(), seeds.end());
  job.out.complete = false;
  const std::uint64_t id = b.SubmitReset(reset_job_);  // throws for a bad index or seed count
  const physics::CommandResult r =
      playing_->manager.session().engine().WaitForCommand(id, kCommandTimeout);
  if (!r.ok()) throw Error("the batch reset failed: " + r.error);
  if (!job.out.complete) throw Error("the batch reset did not complete");
  steps_since_tick_ = 0;
  playing_->manager.Tick();
  return job.out;
}

}  // namespace urlab::embed
