#include "urlab/world/batch_subsystem.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstring>

#include "urlab/control/articulation_control.h"
#include "urlab/core/error.h"
#include "urlab/world/session.h"

namespace urlab::world {

namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool AnyBad(const mjtNum* v, int n) {
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return true;
  }
  return false;
}

void AddSeconds(std::atomic<double>& to, double s) {
  double old = to.load(std::memory_order_relaxed);
  while (!to.compare_exchange_weak(old, old + s, std::memory_order_relaxed)) {
  }
}

}  // namespace

BatchSubsystem::BatchSubsystem(BatchSubsystemOptions options) : options_(options) {
  if (options_.envs < 1) {
    throw Error("--envs must be at least 1 (got " + std::to_string(options_.envs) + ")");
  }
  if (options_.threads < 0) throw Error("--threads must be 0 (the cores) or more");
  if (!(options_.reset_noise >= 0)) throw Error("--reset-noise must be 0 or more");
  if (options_.max_episode_steps < 0) throw Error("--max-episode-steps must be 0 or more");
  auto_reset_.store(options_.auto_reset);
}

BatchSubsystem::~BatchSubsystem() = default;

int BatchSubsystem::threads() const { return others_ ? others_->threads() : 1; }

void BatchSubsystem::BeginPlay(Session& session) {
  session_ = &session;
  physics::PhysicsEngine& engine = session.engine();
  const mjModel* m = engine.model();
  nu_ = m->nu;
  nq_ = m->nq;
  nv_ = m->nv;
  nsensordata_ = m->nsensordata;
  // The session's initial state: every articulation in its initial keyframe (as
  // Session::ResetToInitialState does), the rest in the model's default state.
  std::vector<std::pair<const control::ArticulationControl*, int>> keys;
  for (const Articulation& a : session.articulations()) {
    if (a.initial_key >= 0) keys.emplace_back(a.control, a.initial_key);
  }
  batch_options_.envs = std::max(1, options_.envs - 1);
  batch_options_.threads = options_.threads;
  batch_options_.auto_reset = false;  // next-step autoreset is ours (SubmitStep)
  batch_options_.max_episode_steps = options_.max_episode_steps;
  batch_options_.reset_noise = options_.reset_noise;
  batch_options_.seed = options_.seed + 1;  // environment j of the batch is environment j + 1
  batch_options_.reset_state = [keys](const mjModel* model, mjData* d) {
    mj_resetData(model, d);
    for (const auto& [control, key] : keys) control->ResetToKeyframe(model, d, key);
  };
  if (options_.envs > 1)
    others_ = std::make_unique<physics::Batch>(engine.owned_model(), batch_options_);
  const std::size_t others = static_cast<std::size_t>(options_.envs - 1);
  skip_.assign(others, 0);
  done_.assign(others, 0);
  iteration_done_.assign(others, 0);
  ended_.assign(static_cast<std::size_t>(options_.envs), 0);
  env0_rng_.seed(options_.seed);
  if (options_.reset_noise > 0) {
    // Environment 0 starts like the others: the initial state plus its first noise.
    engine.ResetWith([this](const mjModel* model, mjData* d) { ResetEnv0(model, d, std::nullopt); },
                     "batch reset (environment 0)");
  }
  control::ControlSystem* controls = &session.controls();
  physics::PhysicsEngine* e = &engine;
  engine.SetApplyControlsHook([this, controls, e](const mjModel* model, mjData* d) {
    controls->ApplyControls(model, d, &e->applied_commands());
    ApplyControls(model, d);
  });
  callbacks_.push_back(
      engine.AddOnPostStep([this](const mjModel* model, mjData* d) { PostStep(model, d); }));
  callbacks_.push_back(engine.AddCommandListener(
      [this](const physics::AppliedCommand& c, const mjModel*, const mjData*) { OnCommand(c); }));
  if (options_.envs > 1) {
    spdlog::info("batch: {} environments ({} in the batch beside the engine's own), {} thread(s)",
                 options_.envs, options_.envs - 1, threads());
  }
}

void BatchSubsystem::EndPlay(Session& session) {
  physics::PhysicsEngine& engine = session.engine();
  for (std::uint64_t id : callbacks_) engine.RemoveCallback(id);
  callbacks_.clear();
  control::ControlSystem* controls = &session.controls();
  physics::PhysicsEngine* e = &engine;
  engine.SetApplyControlsHook([controls, e](const mjModel* model, mjData* d) {
    controls->ApplyControls(model, d, &e->applied_commands());
  });
}

std::vector<StatusLine> BatchSubsystem::Status() const {
  if (options_.envs == 1) return {};  // a plain run: nothing to show
  return {{"environments", std::to_string(options_.envs)},
          {"threads", std::to_string(threads())},
          {"environment steps", std::to_string(env_steps())}};
}

// ---------------------------------------------------------------------------------------------
// Physics thread

bool BatchSubsystem::Diverged(const mjModel* m, const mjData* d) {
  // The step core's rule (step_core.cc): a MuJoCo instability warning raised by this step (its
  // lastinfo set), or a non-finite position, velocity or acceleration.
  for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC, mjWARN_BADCTRL}) {
    if (d->warning[w].number > 0 && d->warning[w].lastinfo != -1) return true;
  }
  return AnyBad(d->qpos, m->nq) || AnyBad(d->qvel, m->nv) || AnyBad(d->qacc, m->nv);
}

void BatchSubsystem::ResetEnv0(const mjModel* m, mjData* d, std::optional<std::uint64_t> seed) {
  if (seed) env0_rng_.seed(*seed);
  physics::ResetBatchState(batch_options_, env0_rng_, m, d);
  env0_steps_ = 0;
  env0_diverged_ = false;
}

void BatchSubsystem::SyncOptions(const mjModel* m) {
  // set_sim_options changes the engine's model: the other environments follow.
  if (others_ && std::memcmp(&m->opt, &others_->model()->opt, sizeof(mjOption)) != 0) {
    others_->SetPhysicsOptions(m->opt);
  }
}

void BatchSubsystem::OnCommand(const physics::AppliedCommand& c) {
  // A step command tells its listeners when its window ends. armed_ is done (and dropped) by then
  // when that window was its own; still armed, it belongs to a window that was cancelled before
  // or while it ran (the steps in it were somebody else's, or cut short): dropped too.
  if (std::string_view(c.name) != "step" || !armed_) return;
  armed_.reset();
  window_ = 0;
}

void BatchSubsystem::ApplyControls(const mjModel*, mjData* d) {
  if (!armed_) return;
  // The first iteration that steps after the job was armed is its window's (the engine is paused
  // in direct mode: only step windows step), and so are the next n - 1.
  window_ = 1;
  // Environment 0's actions are raw controls, over what its controllers wrote.
  std::memcpy(d->ctrl, armed_->actions.data(), sizeof(double) * static_cast<std::size_t>(nu_));
}

void BatchSubsystem::StepOthers(const std::vector<double>& actions, std::vector<std::uint8_t>& done,
                                const std::vector<std::uint8_t>& skip) {
  if (!others_) return;
  const std::size_t nu = static_cast<std::size_t>(nu_);
  try {
    others_->Step(std::span<const double>(actions.data() + nu, actions.size() - nu), {},
                  iteration_done_, skip);
  } catch (const std::exception& e) {
    // The environment whose iteration threw is latched (done) until it is reset.
    spdlog::warn("batch: {}", e.what());
  }
  for (std::size_t i = 0; i < done.size(); ++i) done[i] |= iteration_done_[i];
}

void BatchSubsystem::Gather(const mjModel* m, const mjData* d, BatchResult& out) {
  const std::size_t n = static_cast<std::size_t>(options_.envs);
  const std::size_t row = static_cast<std::size_t>(observation_size());
  out.obs.resize(n * row);
  out.time.resize(n);
  out.episode_steps.resize(n);
  out.done.resize(n, 0);
  out.reset.resize(n, 0);
  mju_copy(out.obs.data(), d->qpos, m->nq);
  mju_copy(out.obs.data() + m->nq, d->qvel, m->nv);
  mju_copy(out.obs.data() + m->nq + m->nv, d->sensordata, m->nsensordata);
  out.time[0] = d->time;
  out.episode_steps[0] = env0_steps_;
  for (std::size_t i = 1; i < n; ++i) {
    const int j = static_cast<int>(i - 1);
    others_->ObserveOne(j, out.obs.data() + row * i);
    out.time[i] = others_->env(j).data()->time;
    out.episode_steps[i] = static_cast<std::uint32_t>(others_->episode_steps(j));
  }
}

void BatchSubsystem::PostStep(const mjModel* m, mjData* d) {
  if (!armed_ || window_ == 0) return;
  BatchStepJob& job = *armed_;
  ++iterations_;
  ++env0_steps_;
  if (Diverged(m, d)) env0_diverged_ = true;
  StepOthers(job.actions, done_, skip_);
  if (iterations_ < job.n) return;
  BatchResult& out = job.out;
  out.done.assign(static_cast<std::size_t>(options_.envs), 0);
  out.reset = job.reset;
  Gather(m, d, out);
  out.done[0] =
      env0_diverged_ || (options_.max_episode_steps > 0 &&
                         env0_steps_ >= static_cast<std::uint32_t>(options_.max_episode_steps));
  for (std::size_t i = 0; i < done_.size(); ++i) out.done[i + 1] = done_[i];
  out.seconds = Now() - started_;
  out.complete = true;
  AddSeconds(busy_seconds_, out.seconds);
  env_steps_.fetch_add(
      static_cast<std::uint64_t>(job.n) * static_cast<std::uint64_t>(options_.envs),
      std::memory_order_relaxed);
  armed_.reset();
  window_ = 0;
}

// ---------------------------------------------------------------------------------------------
// Requests

std::uint64_t BatchSubsystem::SubmitStep(std::shared_ptr<BatchStepJob> job, std::uint64_t* steps) {
  if (!session_) throw Error("batch: not playing");
  const std::size_t n = static_cast<std::size_t>(options_.envs);
  if (job->actions.size() != n * static_cast<std::size_t>(nu_)) {
    throw Error("batch: actions hold " + std::to_string(job->actions.size()) +
                " values, expected " + std::to_string(n * static_cast<std::size_t>(nu_)) + " (" +
                std::to_string(n) + " x " + std::to_string(nu_) + ")");
  }
  if (!job->reset.empty() && job->reset.size() != n) {
    throw Error("batch: reset holds " + std::to_string(job->reset.size()) + " flags, expected " +
                std::to_string(n));
  }
  if (job->n < 1) throw Error("batch: n_steps must be at least 1");
  job->reset.resize(n, 0);
  if (auto_reset()) {
    for (std::size_t i = 0; i < n; ++i) job->reset[i] |= ended_[i];
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (job->reset[i]) ended_[i] = 0;
  }
  physics::PhysicsEngine& engine = session_->engine();
  if (job->reset[0]) {
    // Environment 0 resets (and does not step): a command the recorder sees; the others step
    // inside an Inspect command behind it.
    engine.Submit(physics::cmd::ResetCustom{
        [this](const mjModel* m, mjData* d) { ResetEnv0(m, d, std::nullopt); },
        "batch reset (environment 0)"});
    *steps = 0;
    return engine.Submit(physics::cmd::Inspect{
        [this, job](const mjModel* m, const mjData* d) {
          const double t0 = Now();
          SyncOptions(m);
          std::vector<std::uint8_t> skip(job->reset.begin() + 1, job->reset.end());
          std::vector<std::uint8_t> done(skip.size(), 0);
          for (std::size_t i = 0; i < skip.size(); ++i) {
            if (skip[i]) others_->Reset(static_cast<int>(i));
          }
          for (int k = 0; k < job->n; ++k) StepOthers(job->actions, done, skip);
          BatchResult& out = job->out;
          out.done.assign(static_cast<std::size_t>(options_.envs), 0);
          out.reset = job->reset;
          Gather(m, d, out);
          for (std::size_t i = 0; i < done.size(); ++i) out.done[i + 1] = done[i];
          out.seconds = Now() - t0;
          out.complete = true;
          AddSeconds(busy_seconds_, out.seconds);
          env_steps_.fetch_add(static_cast<std::uint64_t>(job->n) * (skip.size() + 1),
                               std::memory_order_relaxed);
        },
        "batch step"});
  }
  engine.Submit(physics::cmd::Inspect{[this, job](const mjModel* m, const mjData*) {
                                        started_ = Now();
                                        SyncOptions(m);
                                        for (std::size_t i = 1; i < job->reset.size(); ++i) {
                                          skip_[i - 1] = job->reset[i];
                                          if (job->reset[i])
                                            others_->Reset(static_cast<int>(i - 1));
                                        }
                                        std::fill(done_.begin(), done_.end(), 0);
                                        armed_ = job;
                                        window_ = 0;
                                        iterations_ = 0;
                                      },
                                      "batch arm"});
  *steps = static_cast<std::uint64_t>(job->n);
  return engine.Submit(physics::cmd::Step{job->n});
}

std::uint64_t BatchSubsystem::SubmitReset(std::shared_ptr<BatchResetJob> job) {
  if (!session_) throw Error("batch: not playing");
  const int n = options_.envs;
  if (job->envs.empty()) {
    for (int i = 0; i < n; ++i) job->envs.push_back(i);
  }
  if (!job->seeds.empty() && job->seeds.size() != job->envs.size()) {
    throw Error("batch: " + std::to_string(job->seeds.size()) + " seeds for " +
                std::to_string(job->envs.size()) + " environments");
  }
  job->seeds.resize(job->envs.size());
  std::vector<std::uint8_t> listed(static_cast<std::size_t>(n), 0);
  for (int env : job->envs) {
    if (env < 0 || env >= n) {
      throw Error("batch: no environment " + std::to_string(env) + " (this run has " +
                  std::to_string(n) + ")");
    }
    if (listed[static_cast<std::size_t>(env)]) {
      throw Error("batch: environment " + std::to_string(env) + " is listed twice");
    }
    listed[static_cast<std::size_t>(env)] = 1;
  }
  physics::PhysicsEngine& engine = session_->engine();
  for (std::size_t k = 0; k < job->envs.size(); ++k) {
    ended_[static_cast<std::size_t>(job->envs[k])] = 0;
    if (job->envs[k] == 0) {
      engine.Submit(physics::cmd::ResetCustom{
          [this, seed = job->seeds[k]](const mjModel* m, mjData* d) { ResetEnv0(m, d, seed); },
          "batch reset (environment 0)"});
    }
  }
  return engine.Submit(
      physics::cmd::Inspect{[this, job, listed](const mjModel* m, const mjData* d) {
                              const double t0 = Now();
                              SyncOptions(m);
                              for (std::size_t k = 0; k < job->envs.size(); ++k) {
                                if (job->envs[k] > 0)
                                  others_->Reset(job->envs[k] - 1, job->seeds[k]);
                              }
                              BatchResult& out = job->out;
                              out.done.assign(listed.size(), 0);
                              out.reset = listed;
                              Gather(m, d, out);
                              out.seconds = Now() - t0;
                              out.complete = true;
                            },
                            "batch reset"});
}

void BatchSubsystem::NoteCompleted(const BatchResult& out) {
  for (std::size_t i = 0; i < ended_.size() && i < out.done.size(); ++i) ended_[i] = out.done[i];
}

}  // namespace urlab::world
