#include "urlab/physics/batch.h"

#include <algorithm>
#include <atomic>
#include <string>
#include <thread>

#include "core/worker_pool.h"
#include "urlab/core/error.h"

namespace urlab::physics {

struct Batch::Env {
  explicit Env(std::shared_ptr<Model> m)
      : model(m),
        core(std::move(m),
             StepCore::Options{.reset_on_divergence = false, .log_command_failures = false}) {
    core.SetEventSink([this](const EngineEvent& e) {
      if (e.kind == EngineEventKind::kDivergence) diverged = true;
    });
  }
  std::shared_ptr<Model> model;  // shared, or its own when randomising
  StepCore core;
  int index = 0;
  std::vector<std::pair<int, double>> qpos_offsets;  // the last draw's
  EnvLatency latency;
  std::unique_ptr<ControlLaw> control;  // null: the actions are the controls
  std::vector<double> observed;         // the observed row, when its observations are delayed
  std::mt19937_64 rng;
  std::uint64_t episode_steps = 0;
  bool diverged = false;  // since the last reset
  std::string error;      // the last iteration threw (reported by Step)
};

namespace {

// Uniform in [-scale, scale] from 53 random bits (the same numbers on every platform).
double Noise(std::mt19937_64& rng, double scale) {
  const double unit = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1)
  return scale * (2 * unit - 1);
}

}  // namespace

// The reset state (custom, keyframe or default), then the noise: positions of hinge, slide and
// free joints (not the free joints' quaternions, nor ball joints), then every velocity.
void ResetBatchState(const BatchOptions& o, std::mt19937_64& rng, const mjModel* m, mjData* d) {
  if (o.reset_state) {
    o.reset_state(m, d);
  } else if (o.keyframe >= 0) {
    mj_resetDataKeyframe(m, d, o.keyframe);
  } else {
    mj_resetData(m, d);
  }
  if (o.reset_noise <= 0) return;
  for (int j = 0; j < m->njnt; ++j) {
    const int type = m->jnt_type[j];
    const int n = type == mjJNT_FREE ? 3 : type == mjJNT_BALL ? 0 : 1;
    for (int k = 0; k < n; ++k) d->qpos[m->jnt_qposadr[j] + k] += Noise(rng, o.reset_noise);
  }
  for (int v = 0; v < m->nv; ++v) d->qvel[v] += Noise(rng, o.reset_noise);
}

Batch::Batch(const Model& model, BatchOptions options) : options_(options) {
  if (options.envs < 1) {
    throw Error("batch: envs must be at least 1 (got " + std::to_string(options.envs) + ")");
  }
  if (options.threads < 0) {
    throw Error("batch: threads must be 0 (the cores) or more (got " +
                std::to_string(options.threads) + ")");
  }
  if (!model) throw Error("batch: no model");
  if (options.keyframe < -1 || options.keyframe >= model->nkey) {
    throw Error("batch: keyframe " + std::to_string(options.keyframe) +
                " out of range (model has " + std::to_string(model->nkey) + ")");
  }
  if (!(options.reset_noise >= 0)) throw Error("batch: reset_noise must be 0 or more");
  if (options.max_episode_steps < 0) throw Error("batch: max_episode_steps must be 0 or more");
  model_ = std::make_shared<Model>(model.Copy());
  envs_.reserve(static_cast<std::size_t>(options.envs));
  for (int i = 0; i < options.envs; ++i) {
    envs_.push_back(
        std::make_unique<Env>(options.randomize ? std::make_shared<Model>(model.Copy()) : model_));
    envs_.back()->index = i;
    if (options.latency) envs_.back()->latency.Configure(options.latency(i));
    if (options.control) envs_.back()->control = options.control(i);
  }
  int threads = options.threads;
  if (threads == 0) threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  part_ = [this](int part) { StepPart(part); };
  pool_ = std::make_unique<WorkerPool>(std::min(threads, options.envs));
  shares_ = std::make_unique<Share[]>(static_cast<std::size_t>(pool_->threads()));
  ResetAll(options.seed);
}

Batch::~Batch() = default;

int Batch::threads() const { return pool_->threads(); }

StepCore& Batch::env(int i) {
  if (i < 0 || i >= envs()) throw Error("batch: no environment " + std::to_string(i));
  return envs_[static_cast<std::size_t>(i)]->core;
}

std::uint64_t Batch::episode_steps(int env) const {
  if (env < 0 || env >= envs()) throw Error("batch: no environment " + std::to_string(env));
  return envs_[static_cast<std::size_t>(env)]->episode_steps;
}

void Batch::ResetEnv(Env& e, std::optional<std::uint64_t> seed) {
  // Randomised: the draw goes into the environment's own model first (nobody steps it now).
  if (options_.randomize) {
    BatchOptions::Draw draw;
    options_.randomize(e.index, seed, e.model->get(), &draw);
    e.qpos_offsets = std::move(draw.qpos_offsets);
    e.latency.SetNoise(draw.noise);
  }
  // Through the command table like any reset: the core's divergence episode ends, its readers
  // see the discontinuity.
  e.core.commands().Push(cmd::ResetCustom{[this, &e](const mjModel* m, mjData* d) {
                                            ResetBatchState(options_, e.rng, m, d);
                                            for (const auto& [adr, offset] : e.qpos_offsets)
                                              d->qpos[adr] += offset;
                                          },
                                          "batch reset"});
  e.core.SetPaused(false);  // clears an error latch
  e.core.ApplyPending();
  if (e.control) e.control->Restart();
  RestartLatency(e);
  e.episode_steps = 0;
  e.diverged = false;
}

void Batch::Reset(int env, std::optional<std::uint64_t> seed) {
  if (env < 0 || env >= envs()) throw Error("batch: no environment " + std::to_string(env));
  Env& e = *envs_[static_cast<std::size_t>(env)];
  if (seed) e.rng.seed(*seed);
  ResetEnv(e, seed);
}

void Batch::ResetAll(std::optional<std::uint64_t> seed) {
  for (int i = 0; i < envs(); ++i) {
    Reset(i, seed ? std::optional<std::uint64_t>(*seed + static_cast<std::uint64_t>(i))
                  : std::nullopt);
  }
}

void Batch::RestartLatency(Env& e) {
  if (!e.latency.controls_delayed() && !e.latency.observations_delayed()) return;
  e.observed.resize(static_cast<std::size_t>(observation_size()));
  ObserveTrue(e, e.observed.data());
  e.latency.Restart(e.core.data(), e.observed.data());
}

void Batch::ObserveEnv(const Env& e, double* out) const {
  if (e.latency.observations_delayed()) {
    mju_copy(out, e.observed.data(), observation_size());
    return;
  }
  ObserveTrue(e, out);
}

void Batch::ObserveTrue(const Env& e, double* out) const {
  const mjModel* m = model();
  const mjData* d = e.core.data();
  mju_copy(out, d->qpos, m->nq);
  mju_copy(out + m->nq, d->qvel, m->nv);
  mju_copy(out + m->nq + m->nv, d->sensordata, m->nsensordata);
}

void Batch::ObserveOne(int env, double* out) const {
  if (env < 0 || env >= envs()) throw Error("batch: no environment " + std::to_string(env));
  ObserveEnv(*envs_[static_cast<std::size_t>(env)], out);
}

bool Batch::diverged(int env) const {
  if (env < 0 || env >= envs()) throw Error("batch: no environment " + std::to_string(env));
  const Env& e = *envs_[static_cast<std::size_t>(env)];
  return e.diverged || e.core.error_latched();
}

void Batch::SetPhysicsOptions(const mjOption& opt, bool keep_gravity) {
  const auto set = [&](mjModel* m) {
    mjtNum gravity[3];
    mju_copy3(gravity, m->opt.gravity);
    m->opt = opt;
    if (keep_gravity) mju_copy3(m->opt.gravity, gravity);
  };
  set(model_->get());
  if (options_.randomize) {
    for (auto& e : envs_) set(e->model->get());
  }
}

const mjModel* Batch::model(int env) const {
  if (env < 0 || env >= envs()) throw Error("batch: no environment " + std::to_string(env));
  return envs_[static_cast<std::size_t>(env)]->model->get();
}

void Batch::Observe(std::span<double> observations) const {
  const std::size_t row = static_cast<std::size_t>(observation_size());
  if (observations.size() != row * envs_.size()) {
    throw Error("batch: observations hold " + std::to_string(observations.size()) +
                " values, expected " + std::to_string(row * envs_.size()) + " (" +
                std::to_string(envs()) + " x " + std::to_string(row) + ")");
  }
  for (std::size_t i = 0; i < envs_.size(); ++i)
    ObserveEnv(*envs_[i], observations.data() + row * i);
}

void Batch::StepEnv(Env& e, const double* action, double* obs, std::uint8_t* done) {
  if (e.core.error_latched() && !options_.auto_reset) {  // failed earlier: waits for a reset
    if (done) *done = 1;
    if (obs) ObserveEnv(e, obs);
    return;
  }
  mjData* d = e.core.data();
  mju_copy(d->ctrl, action, model()->nu);
  if (e.latency.controls_delayed()) e.latency.ApplyControl(action, d);
  try {
    if (e.control) e.control->Apply(e.model->get(), d);  // the actions in ctrl: its targets
    e.core.Advance({.force_step = true, .honour_error_latch = false});
    if (e.latency.observations_delayed()) {
      ObserveTrue(e, e.observed.data());
      e.latency.Observe(e.observed.data());
    }
  } catch (const std::exception& ex) {
    e.core.Fail(ex);
    e.error = ex.what();
    e.diverged = true;
  }
  ++e.episode_steps;
  const bool ended =
      e.diverged || (options_.max_episode_steps > 0 &&
                     e.episode_steps >= static_cast<std::uint64_t>(options_.max_episode_steps));
  if (done) *done = ended ? 1 : 0;
  if (ended && options_.auto_reset) {
    ResetEnv(e);
    e.error.clear();
  }
  if (obs) ObserveEnv(e, obs);
}

void Batch::Step(std::span<const double> actions, std::span<double> observations,
                 std::span<std::uint8_t> done, std::span<const std::uint8_t> skip, int iterations) {
  StepBegin(actions, observations, done, skip, iterations);
  StepEnd();
}

void Batch::StepBegin(std::span<const double> actions, std::span<double> observations,
                      std::span<std::uint8_t> done, std::span<const std::uint8_t> skip,
                      int iterations) {
  if (pool_->started()) StepEnd();
  if (iterations < 1) {
    throw Error("batch: iterations must be at least 1 (got " + std::to_string(iterations) + ")");
  }
  const std::size_t n = envs_.size();
  const std::size_t nu = static_cast<std::size_t>(action_size());
  const std::size_t row = static_cast<std::size_t>(observation_size());
  if (actions.size() != nu * n) {
    throw Error("batch: actions hold " + std::to_string(actions.size()) + " values, expected " +
                std::to_string(nu * n) + " (" + std::to_string(n) + " x " + std::to_string(nu) +
                ")");
  }
  if (!observations.empty() && observations.size() != row * n) {
    throw Error("batch: observations hold " + std::to_string(observations.size()) +
                " values, expected " + std::to_string(row * n) + " (" + std::to_string(n) + " x " +
                std::to_string(row) + ")");
  }
  if (!done.empty() && done.size() != n) {
    throw Error("batch: done holds " + std::to_string(done.size()) + " flags, expected " +
                std::to_string(n));
  }
  if (!skip.empty() && skip.size() != n) {
    throw Error("batch: skip holds " + std::to_string(skip.size()) + " flags, expected " +
                std::to_string(n));
  }
  pass_.actions = actions;
  pass_.observations = observations;
  pass_.done = done;
  pass_.skip = skip;
  pass_.iterations = iterations;
  const std::size_t parts = static_cast<std::size_t>(pool_->threads());
  for (std::size_t k = 0; k < parts; ++k) {
    shares_[k].next.store(k * n / parts, std::memory_order_relaxed);
    shares_[k].end = (k + 1) * n / parts;
  }
  pool_->Start(part_);  // publishes pass_ to the workers
}

void Batch::StepPart(int part) {
  // Each thread first claims environments from the front of its own share, then from the
  // others' once its own are done: an environment stays on one thread (its data in that core's
  // caches) from step to step while the threads keep pace, and a thread the machine preempts
  // holds back only the environment it is stepping, the others take the rest of its share.
  const std::size_t nu = static_cast<std::size_t>(action_size());
  const std::size_t row = static_cast<std::size_t>(observation_size());
  const Pass& p = pass_;
  const std::size_t parts = static_cast<std::size_t>(pool_->threads());
  for (std::size_t r = 0; r < parts; ++r) {
    Share& share = shares_[(static_cast<std::size_t>(part) + r) % parts];
    for (std::size_t i = share.next.fetch_add(1, std::memory_order_relaxed); i < share.end;
         i = share.next.fetch_add(1, std::memory_order_relaxed)) {
      double* obs = p.observations.empty() ? nullptr : p.observations.data() + row * i;
      if (!p.skip.empty() && p.skip[i]) {
        if (!p.done.empty()) p.done[i] = 0;
        if (obs) ObserveEnv(*envs_[i], obs);
        continue;
      }
      // All of the call's iterations of this environment, one after another (its data stays in
      // this core's caches); the observation after the last.
      const double* action = p.actions.data() + nu * i;
      std::uint8_t ended = 0;
      for (int k = 0; k < p.iterations; ++k) {
        std::uint8_t d = 0;
        StepEnv(*envs_[i], action, k + 1 == p.iterations ? obs : nullptr, &d);
        ended |= d;
      }
      if (!p.done.empty()) p.done[i] = ended;
    }
  }
}

void Batch::Settle() {
  if (!pool_->started()) return;
  try {
    StepEnd();
  } catch (const std::exception&) {  // the environment stays latched until it is reset
  }
}

void Batch::StepEnd() {
  if (!pool_->started()) return;
  pool_->Finish();
  for (std::size_t i = 0; i < envs_.size(); ++i) {
    if (envs_[i]->error.empty()) continue;
    std::string error = std::move(envs_[i]->error);
    envs_[i]->error.clear();
    throw Error("batch: environment " + std::to_string(i) + ": " + error +
                " (it stays as it is until it is reset)");
  }
}

}  // namespace urlab::physics
