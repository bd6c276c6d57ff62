#include "urlab/world/batch_subsystem.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "urlab/control/articulation_control.h"
#include "urlab/core/error.h"
#include "urlab/physics/latency.h"
#include "urlab/world/session.h"
#include "world/env_controls.h"
#include "world/randomizer.h"

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

std::vector<physics::EnvLatency::Group> BatchSubsystem::LatencyGroups(int env) const {
  // Environment `env` draws its jitter from the run's latency seed + env (environment 0: the
  // seed itself, as the single-environment run), each articulation's channel from its own stream
  // (physics::LatencySeed, as Session::SetLatency).
  std::vector<physics::EnvLatency::Group> groups;
  const std::uint64_t seed = latency_seed_ + static_cast<std::uint64_t>(env);
  for (const LatencyTemplate& t : latency_) {
    using physics::LatencyChannel;
    physics::EnvLatency::Group g;
    g.actuators = t.actuators;
    g.observed = t.observed;
    g.control =
        physics::ResolveLatency(t.latency.control, timestep_,
                                physics::LatencySeed(seed, t.index, LatencyChannel::kControl));
    g.observation =
        physics::ResolveLatency(t.latency.observation, timestep_,
                                physics::LatencySeed(seed, t.index, LatencyChannel::kObservation));
    groups.push_back(std::move(g));
  }
  return groups;
}

BatchSubsystem::BatchSubsystem(BatchSubsystemOptions options) : options_(options) {
  if (options_.envs < 1) {
    throw Error("--envs must be at least 1 (got " + std::to_string(options_.envs) + ")");
  }
  if (options_.threads < 0) throw Error("--threads must be 0 (the cores) or more");
  if (!(options_.reset_noise >= 0)) throw Error("--reset-noise must be 0 or more");
  if (options_.max_episode_steps < 0) throw Error("--max-episode-steps must be 0 or more");
  if (options_.engine_env < 0 || options_.engine_env >= options_.envs) {
    throw Error("--record-env " + std::to_string(options_.engine_env) +
                ": no such environment (--envs " + std::to_string(options_.envs) + " has 0.." +
                std::to_string(options_.envs - 1) + ")");
  }
  if (options_.detached) options_.engine_env = -1;  // no environment is the engine's
  auto_reset_.store(options_.auto_reset);
}

BatchSubsystem::~BatchSubsystem() {
  if (others_) others_->Settle();  // a step begun reads arrays destroyed before the batch
}

int BatchSubsystem::threads() const { return others_ ? others_->threads() : 1; }

void BatchSubsystem::WithEnvironment(int env,
                                     const std::function<void(const mjModel*, const mjData*)>& fn) {
  if (env < 0 || env >= options_.envs) {
    throw Error("batch: no environment " + std::to_string(env) + " (have " +
                std::to_string(options_.envs) + ")");
  }
  if (!session_) throw Error("batch: not playing");
  session_->engine().WithLockedData([&](mjModel* m, mjData* d) {
    if (!detached() && env == options_.engine_env) {
      fn(m, d);
      return;
    }
    const int j = Other(env);
    fn(others_->model(j), others_->env(j).data());
  });
}

void BatchSubsystem::BeginPlay(Session& session) {
  session_ = &session;
  physics::PhysicsEngine& engine = session.engine();
  const mjModel* m = engine.model();
  nu_ = m->nu;
  nq_ = m->nq;
  nv_ = m->nv;
  nsensordata_ = m->nsensordata;
  action_low_.clear();
  action_high_.clear();
  for (int i = 0; i < m->nu; ++i) {
    const bool limited = m->actuator_ctrllimited[i] != 0;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    action_low_.push_back(limited ? m->actuator_ctrlrange[2 * i] : -kInf);
    action_high_.push_back(limited ? m->actuator_ctrlrange[2 * i + 1] : kInf);
  }
  // The scene's controllers in every environment (the engine's environment's here; the batch
  // asks for the others' below): the actions are their targets.
  env_controls_.assign(static_cast<std::size_t>(options_.envs), nullptr);
  if (!options_.raw_actions && EnvControls::Needed(session)) {
    auto controls = std::make_unique<EnvControls>(session);
    controls->TargetBounds(&action_low_, &action_high_);  // over the ctrlranges above
    if (!detached()) {
      env_controls_[static_cast<std::size_t>(options_.engine_env)] = controls.get();
      env0_controls_ = std::move(controls);
    }
    batch_options_.control = [this](int j) {
      auto c = std::make_unique<EnvControls>(*session_);
      env_controls_[static_cast<std::size_t>(Wire(j))] = c.get();
      return c;
    };
  }
  batch_options_.envs = detached() ? options_.envs : std::max(1, options_.envs - 1);
  batch_options_.threads = options_.threads;
  batch_options_.auto_reset = false;  // next-step autoreset is ours (SubmitStep)
  batch_options_.max_episode_steps = options_.max_episode_steps;
  batch_options_.reset_noise = options_.reset_noise;
  batch_options_.seed = options_.seed;  // reseeded below: environment e starts with seed + e
  // The session's initial state: every articulation in its initial keyframe (as
  // Session::ResetToInitialState does), the rest in the model's default state.
  batch_options_.reset_state = session.InitialStateReset();
  // Emulated latency (the scene's `latency:`, as set when play began): per articulation, its
  // actuators and the entries of the observation row that are its state.
  latency_seed_ = session.latency_seed();
  timestep_ = m->opt.timestep;
  for (std::size_t i = 0; i < session.articulations().size(); ++i) {
    const Articulation& a = session.articulations()[i];
    std::vector<int> observed;
    for (const physics::JointView& j : a.bindings->joints().all()) {
      for (int k = 0; k < j.qpos_size; ++k) observed.push_back(j.qpos_adr + k);
    }
    for (const physics::JointView& j : a.bindings->joints().all()) {
      for (int k = 0; k < j.dof_size; ++k) observed.push_back(m->nq + j.dof_adr + k);
    }
    for (const physics::SensorView& v : a.bindings->sensors().all()) {
      for (int k = 0; k < v.dim; ++k) observed.push_back(m->nq + m->nv + v.adr + k);
    }
    observed_.push_back(observed);
    const physics::ArticulationLatency latency = session.Latency(a.name());
    if (latency.control.empty() && latency.observation.empty()) continue;
    LatencyTemplate t{.index = i, .latency = latency, .observed = std::move(observed)};
    for (const physics::ActuatorView& v : a.bindings->actuators().all()) {
      t.actuators.push_back(v.id);
    }
    latency_.push_back(std::move(t));
  }
  if (!latency_.empty()) {
    batch_options_.latency = [this](int j) { return LatencyGroups(Wire(j)); };
  }
  // Domain randomisation (the scene's `randomize:`): every environment draws into a model of its
  // own at each of its resets, from a stream of its own (Draw).
  if (session.randomizes()) {
    randomizer_ = session.randomizer();
    randomize_ = RandomizeOf(session.scene_config()).config;
    randomize_gravity_ = !randomize_.gravity.empty();
    for (int w = 0; w < options_.envs; ++w) {
      draws_.push_back({options_.seed + static_cast<std::uint64_t>(w), 0});
    }
    batch_options_.randomize = [this](int j, std::optional<std::uint64_t> seed, mjModel* model,
                                      physics::BatchOptions::Draw* draw) {
      Draw(Wire(j), seed, model, draw);
    };
  }
  if (options_.envs > 1 || detached()) {
    others_ = std::make_unique<physics::Batch>(engine.owned_model(), batch_options_);
    for (int j = 0; j < others_->envs(); ++j) others_->Reset(j, options_.seed + Wire(j));
  }
  const std::size_t others = static_cast<std::size_t>(others_ ? others_->envs() : 0);
  skip_.assign(others, 0);
  done_.assign(others, 0);
  iteration_done_.assign(others, 0);
  others_obs_.assign(others * static_cast<std::size_t>(observation_size()), 0.0);
  others_observed_ = false;
  ended_.assign(static_cast<std::size_t>(options_.envs), 0);
  if (detached()) {
    // The engine's simulation is no environment: it stays as the session left it, unstepped.
    spdlog::info("batch: {} environments, {} thread(s), detached from the engine", options_.envs,
                 threads());
    return;
  }
  env0_rng_.seed(options_.seed + static_cast<std::uint64_t>(options_.engine_env));
  env0_latency_.Configure(LatencyGroups(options_.engine_env));
  if (options_.reset_noise > 0 || randomizer_) {
    // Environment 0 starts like the others: the initial state plus its first noise and its first
    // draw (the session's own first draw came from the same stream: it is drawn again).
    engine.ResetWith([this](const mjModel* model, mjData* d) { ResetEnv0(model, d, std::nullopt); },
                     "batch reset (environment 0)");
  } else if (!latency_.empty()) {
    engine.WithLockedData([this](mjModel*, mjData* d) { RestartEnv0Latency(d); });
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
    spdlog::info(
        "batch: {} environments ({} in the batch beside the engine's own, environment {}: the "
        "topics, the viewer and recordings follow it), {} thread(s)",
        options_.envs, options_.envs - 1, options_.engine_env, threads());
  }
}

void BatchSubsystem::EndPlay(Session& session) {
  physics::PhysicsEngine& engine = session.engine();
  if (others_) engine.WithLockedData([this](mjModel*, mjData*) { others_->Settle(); });
  if (detached()) return;  // no hooks were installed
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

void BatchSubsystem::Draw(int env, std::optional<std::uint64_t> seed, mjModel* m,
                          physics::BatchOptions::Draw* draw) {
  // Environment `env` draws its n-th randomised reset from Randomizer::ResetSeed(base, n): base
  // is the run's seed + env until a reset gives a seed (batch_reset), which becomes the base.
  Stream& s = draws_[static_cast<std::size_t>(env)];
  if (seed) s = {*seed, 0};
  // The PD gains drawn go to this environment's own controllers (none: drawn, not written).
  const std::uint64_t draw_seed = Randomizer::ResetSeed(s.base, s.n++);
  const EnvControls* controls = env_controls_[static_cast<std::size_t>(env)];
  Randomizer::Applied applied = randomizer_->Apply(
      randomize_, draw_seed, m,
      [controls](std::size_t target) { return controls ? controls->pd(target) : nullptr; });
  draw->qpos_offsets = std::move(applied.qpos_offsets);
  // obs_noise: on the articulation's entries of the observation row, its stream derived from
  // the draw's seed and the articulation (as Session::ResetRandomized seeds it).
  draw->noise.clear();
  for (const auto& [target, stddev] : applied.obs_noise) {
    for (std::size_t i = 0; i < observed_.size(); ++i) {
      if (session_->articulations()[i].name() != target) continue;
      draw->noise.push_back({observed_[i], stddev, physics::DeriveSeed(draw_seed, 1000 + i)});
    }
  }
}

void BatchSubsystem::ResetEnv0(const mjModel* m, mjData* d, std::optional<std::uint64_t> seed) {
  if (seed) env0_rng_.seed(*seed);
  physics::BatchOptions::Draw draw;
  if (randomizer_) {
    // The engine's own model: this runs as one of its commands (or StepHere), with the step
    // mutex held, as Session::ResetRandomized writes it under WithLockedData.
    Draw(options_.engine_env, seed, const_cast<mjModel*>(m), &draw);
    env0_latency_.SetNoise(draw.noise);
  }
  physics::ResetBatchState(batch_options_, env0_rng_, m, d);
  for (const auto& [adr, offset] : draw.qpos_offsets) d->qpos[adr] += offset;
  env0_steps_ = 0;
  env0_diverged_ = false;
  if (env0_controls_) env0_controls_->Restart();
  RestartEnv0Latency(d);
}

void BatchSubsystem::RestartEnv0Latency(const mjData* d) {
  // The controls the reset left prime the control lines now; the observation lines take the row
  // right after the reset (after the command's mj_forward: its sensors) before the next step or
  // gather (ObserveEnv0).
  env0_latency_.RestartControl(d);
  env0_restart_observation_ = env0_latency_.observations_delayed();
}

void BatchSubsystem::TrueRow(const mjModel* m, const mjData* d, double* row) {
  mju_copy(row, d->qpos, m->nq);
  mju_copy(row + m->nq, d->qvel, m->nv);
  mju_copy(row + m->nq + m->nv, d->sensordata, m->nsensordata);
}

void BatchSubsystem::ObserveEnv0(const mjModel* m, const mjData* d, bool stepped) {
  if (!env0_latency_.observations_delayed()) return;
  env0_observed_.resize(static_cast<std::size_t>(observation_size()));
  if (env0_restart_observation_) {
    // The first step after a reset: the reset's state is tick 0 (d is still that state when
    // called before the step).
    env0_restart_observation_ = false;
    TrueRow(m, d, env0_observed_.data());
    env0_latency_.RestartObservation(env0_observed_.data());
  }
  if (!stepped) return;
  TrueRow(m, d, env0_observed_.data());
  env0_latency_.Observe(env0_observed_.data());
}

void BatchSubsystem::SyncOptions(const mjModel* m) {
  // set_sim_options changes the engine's model: the other environments follow (each keeps its
  // own gravity when gravity is drawn per environment).
  if (!others_) return;
  mjOption opt = m->opt;
  if (randomize_gravity_) mju_copy3(opt.gravity, others_->model()->opt.gravity);
  if (std::memcmp(&opt, &others_->model()->opt, sizeof(mjOption)) != 0) {
    others_->SetPhysicsOptions(opt, randomize_gravity_);
  }
}

void BatchSubsystem::OnCommand(const physics::AppliedCommand& c) {
  // A step command tells its listeners when its window ends. armed_ is done (and dropped) by then
  // when that window was its own; still armed, it belongs to a window that was cancelled before
  // or while it ran (the steps in it were somebody else's, or cut short): dropped too.
  if (std::string_view(c.name) != "step" || !armed_) return;
  armed_.reset();
  window_ = 0;
  others_observed_ = false;
}

void BatchSubsystem::ApplyControls(const mjModel* m, mjData* d) {
  if (!armed_) return;
  // The first iteration that steps after the job was armed is its window's (the engine is paused
  // in direct mode: only step windows step), and so are the next n - 1.
  window_ = 1;
  // The engine's environment's actions are raw controls, over what its controllers wrote.
  const double* row = armed_->actions.data() +
                      static_cast<std::size_t>(options_.engine_env) * static_cast<std::size_t>(nu_);
  std::memcpy(d->ctrl, row, sizeof(double) * static_cast<std::size_t>(nu_));
  if (env0_restart_observation_) ObserveEnv0(m, d, /*stepped=*/false);  // the reset's tick 0
  if (env0_latency_.controls_delayed()) env0_latency_.ApplyControl(row, d);
  if (env0_controls_) env0_controls_->Apply(m, d);  // as the batch's environments do theirs
  // The other environments start stepping on the workers while this thread steps the engine's;
  // PostStep joins them (StepOthers). In the window's last iteration the stepping threads also
  // write their observation rows (each from its own core's caches), for Gather.
  if (others_) {
    const bool last = iterations_ + 1 >= armed_->n;
    others_observed_ = false;
    try {
      others_->StepBegin(
          OthersRows(armed_->actions, static_cast<std::size_t>(nu_), &others_actions_),
          last ? std::span<double>(others_obs_) : std::span<double>(), iteration_done_, skip_);
      others_observed_ = last;
    } catch (const std::exception& e) {
      spdlog::warn("batch: {}", e.what());
    }
  }
}

template <typename T>
std::span<const T> BatchSubsystem::OthersRows(const std::vector<T>& all, std::size_t width,
                                              std::vector<T>* scratch) const {
  // Rows in the batch's order: every environment's but the engine's.
  if (detached()) return all;
  const std::size_t e = static_cast<std::size_t>(options_.engine_env);
  if (e == 0) return std::span<const T>(all.data() + width, all.size() - width);
  scratch->assign(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(e * width));
  scratch->insert(scratch->end(), all.begin() + static_cast<std::ptrdiff_t>((e + 1) * width),
                  all.end());
  return *scratch;
}

void BatchSubsystem::StepOthers(const std::vector<double>& actions, std::vector<std::uint8_t>& done,
                                const std::vector<std::uint8_t>& skip, bool begun) {
  if (!others_) return;
  try {
    if (begun) {
      others_->StepEnd();
    } else {
      others_->Step(OthersRows(actions, static_cast<std::size_t>(nu_), &others_actions_), {},
                    iteration_done_, skip);
    }
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
  // Detached, every row is the batch's: the engine's simulation is none of them.
  if (!detached()) {
    const std::size_t e = static_cast<std::size_t>(options_.engine_env);
    double* engine_row = out.obs.data() + row * e;
    if (env0_latency_.observations_delayed()) {
      if (env0_restart_observation_) ObserveEnv0(m, d, /*stepped=*/false);  // reset, not stepped
      mju_copy(engine_row, env0_observed_.data(), static_cast<int>(row));
    } else {
      TrueRow(m, d, engine_row);
    }
    out.time[e] = d->time;
    out.episode_steps[e] = env0_steps_;
    // The others' rows: as the stepping threads wrote them in this window's last iteration (the
    // rows before the engine's environment, then those after it), or read below. (Only a
    // window's last iteration sets others_observed_: never detached.)
    if (others_ && others_observed_) {
      const std::size_t before = e * row;
      std::copy_n(others_obs_.data(), before, out.obs.data());
      std::copy_n(others_obs_.data() + before, others_obs_.size() - before,
                  out.obs.data() + before + row);
    }
  }
  for (int j = 0; others_ && j < others_->envs(); ++j) {
    const std::size_t i = static_cast<std::size_t>(Wire(j));
    if (!others_observed_) others_->ObserveOne(j, out.obs.data() + row * i);
    out.time[i] = others_->env(j).data()->time;
    out.episode_steps[i] = static_cast<std::uint32_t>(others_->episode_steps(j));
  }
  others_observed_ = false;
}

void BatchSubsystem::PostStep(const mjModel* m, mjData* d) {
  if (!armed_ || window_ == 0) return;
  BatchStepJob& job = *armed_;
  ++iterations_;
  ++env0_steps_;
  if (Diverged(m, d)) env0_diverged_ = true;
  ObserveEnv0(m, d, /*stepped=*/true);
  StepOthers(job.actions, done_, skip_, /*begun=*/true);
  if (iterations_ < job.n) return;
  BatchResult& out = job.out;
  out.done.assign(static_cast<std::size_t>(options_.envs), 0);
  out.reset = job.reset;
  Gather(m, d, out);
  out.done[static_cast<std::size_t>(options_.engine_env)] =
      env0_diverged_ || (options_.max_episode_steps > 0 &&
                         env0_steps_ >= static_cast<std::uint32_t>(options_.max_episode_steps));
  for (std::size_t j = 0; j < done_.size(); ++j) {
    out.done[static_cast<std::size_t>(Wire(static_cast<int>(j)))] = done_[j];
  }
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

void BatchSubsystem::CheckStep(const BatchStepJob& job) const {
  if (!session_) throw Error("batch: not playing");
  const std::size_t n = static_cast<std::size_t>(options_.envs);
  if (job.actions.size() != n * static_cast<std::size_t>(nu_)) {
    throw Error("batch: actions hold " + std::to_string(job.actions.size()) + " values, expected " +
                std::to_string(n * static_cast<std::size_t>(nu_)) + " (" + std::to_string(n) +
                " x " + std::to_string(nu_) + ")");
  }
  if (!job.reset.empty() && job.reset.size() != n) {
    throw Error("batch: reset holds " + std::to_string(job.reset.size()) + " flags, expected " +
                std::to_string(n));
  }
  if (job.n < 1) throw Error("batch: n_steps must be at least 1");
}

void BatchSubsystem::TakeResets(BatchStepJob& job) {
  const std::size_t n = static_cast<std::size_t>(options_.envs);
  job.reset.resize(n, 0);
  if (auto_reset()) {
    for (std::size_t i = 0; i < n; ++i) job.reset[i] |= ended_[i];
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (job.reset[i]) ended_[i] = 0;
  }
}

void BatchSubsystem::Arm(const std::shared_ptr<BatchStepJob>& job, const mjModel* m) {
  started_ = Now();
  if (others_) others_->Settle();
  SyncOptions(m);
  for (std::size_t j = 0; j < skip_.size(); ++j) {
    skip_[j] = job->reset[static_cast<std::size_t>(Wire(static_cast<int>(j)))];
    if (skip_[j]) others_->Reset(static_cast<int>(j));
  }
  std::fill(done_.begin(), done_.end(), 0);
  others_observed_ = false;
  armed_ = job;
  window_ = 0;
  iterations_ = 0;
}

bool BatchSubsystem::StepHere(const std::shared_ptr<BatchStepJob>& job) {
  CheckStep(*job);
  if (detached()) {
    StepDetached(*job);
    return true;
  }
  // Environment 0 resetting in this step goes through its commands (SubmitStep).
  const std::size_t e = static_cast<std::size_t>(options_.engine_env);
  const bool reset0 = (!job->reset.empty() && job->reset[e]) || (auto_reset() && ended_[e]);
  physics::PhysicsEngine& engine = session_->engine();
  if (reset0 || !engine.paused()) return false;
  TakeResets(*job);
  engine.WithLockedData([this, &job](mjModel* m, mjData*) { Arm(job, m); });
  try {
    engine.StepSync(job->n);
  } catch (...) {
    // The window stopped part-way (a MuJoCo error, or the loop unpaused meanwhile): the job
    // does not complete, and no later iteration may take it for its own.
    engine.WithLockedData([this](mjModel*, mjData*) {
      armed_.reset();
      window_ = 0;
    });
    throw;
  }
  return true;
}

std::uint64_t BatchSubsystem::SubmitStep(std::shared_ptr<BatchStepJob> job, std::uint64_t* steps) {
  CheckStep(*job);
  if (detached()) throw Error("batch: a detached batch steps only on its requester (StepHere)");
  TakeResets(*job);
  physics::PhysicsEngine& engine = session_->engine();
  if (job->reset[static_cast<std::size_t>(options_.engine_env)]) {
    // The engine's environment resets (and does not step): a command the recorder sees; the others
    // step inside an Inspect command behind it.
    engine.Submit(physics::cmd::ResetCustom{
        [this](const mjModel* m, mjData* d) { ResetEnv0(m, d, std::nullopt); },
        "batch reset (environment 0)"});
    *steps = 0;
    return engine.Submit(physics::cmd::Inspect{
        [this, job](const mjModel* m, const mjData* d) {
          const double t0 = Now();
          if (others_) others_->Settle();
          SyncOptions(m);
          std::vector<std::uint8_t> rows;
          const std::span<const std::uint8_t> flags = OthersRows(job->reset, 1, &rows);
          const std::vector<std::uint8_t> skip(flags.begin(), flags.end());
          std::vector<std::uint8_t> done(skip.size(), 0);
          for (std::size_t i = 0; i < skip.size(); ++i) {
            if (skip[i]) others_->Reset(static_cast<int>(i));
          }
          for (int k = 0; k < job->n; ++k) StepOthers(job->actions, done, skip);
          BatchResult& out = job->out;
          out.done.assign(static_cast<std::size_t>(options_.envs), 0);
          out.reset = job->reset;
          Gather(m, d, out);
          for (std::size_t j = 0; j < done.size(); ++j) {
            out.done[static_cast<std::size_t>(Wire(static_cast<int>(j)))] = done[j];
          }
          out.seconds = Now() - t0;
          out.complete = true;
          AddSeconds(busy_seconds_, out.seconds);
          env_steps_.fetch_add(static_cast<std::uint64_t>(job->n) * (skip.size() + 1),
                               std::memory_order_relaxed);
        },
        "batch step"});
  }
  engine.Submit(physics::cmd::Inspect{[this, job](const mjModel* m, const mjData*) { Arm(job, m); },
                                      "batch arm"});
  submitted_ = job;
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
    if (!detached() && job->envs[k] == options_.engine_env) {
      engine.Submit(physics::cmd::ResetCustom{
          [this, seed = job->seeds[k]](const mjModel* m, mjData* d) { ResetEnv0(m, d, seed); },
          "batch reset (environment 0)"});
    }
  }
  return engine.Submit(
      physics::cmd::Inspect{[this, job, listed](const mjModel* m, const mjData* d) {
                              const double t0 = Now();
                              if (others_) others_->Settle();
                              SyncOptions(m);
                              for (std::size_t k = 0; k < job->envs.size(); ++k) {
                                if (detached() || job->envs[k] != options_.engine_env)
                                  others_->Reset(Other(job->envs[k]), job->seeds[k]);
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

void BatchSubsystem::StepDetached(BatchStepJob& job) {
  // Every environment is the batch's: the requesting thread and the workers step them all, with
  // the step mutex held (the commands of a reset, applied by the physics thread, touch them too).
  TakeResets(job);
  physics::PhysicsEngine& engine = session_->engine();
  engine.WithLockedData([this, &job](mjModel* m, mjData*) {
    const double t0 = Now();
    others_->Settle();
    SyncOptions(m);
    for (std::size_t j = 0; j < job.reset.size(); ++j) {
      if (job.reset[j]) others_->Reset(static_cast<int>(j));
    }
    BatchResult& out = job.out;
    const std::size_t n = static_cast<std::size_t>(options_.envs);
    out.obs.resize(n * static_cast<std::size_t>(observation_size()));
    out.done.assign(n, 0);
    // All n iterations in one pass: each environment's n steps run one after another on the
    // thread that claimed it (its data stays in that core's caches; the threads meet once, not
    // n times), and its last writes its observation row. No environment depends on another, so
    // the bits are those of n passes of one iteration.
    try {
      others_->Step(job.actions, out.obs, iteration_done_, job.reset, job.n);
    } catch (const std::exception& e) {
      // The environment whose iteration threw is latched (done) until it is reset.
      spdlog::warn("batch: {}", e.what());
      others_->Observe(out.obs);
    }
    for (std::size_t i = 0; i < n; ++i) out.done[i] = iteration_done_[i];
    out.reset = job.reset;
    out.time.resize(n);
    out.episode_steps.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      out.time[i] = others_->env(static_cast<int>(i)).data()->time;
      out.episode_steps[i] =
          static_cast<std::uint32_t>(others_->episode_steps(static_cast<int>(i)));
    }
    out.seconds = Now() - t0;
    out.complete = true;
    AddSeconds(busy_seconds_, out.seconds);
    env_steps_.fetch_add(static_cast<std::uint64_t>(job.n) * n, std::memory_order_relaxed);
  });
}

void BatchSubsystem::Disarm() {
  if (!session_ || !submitted_) return;
  // Only that job: a later one (armed by StepHere before this command applied) stays armed.
  session_->engine().Submit(
      physics::cmd::Inspect{[this, job = std::move(submitted_)](const mjModel*, const mjData*) {
                              if (armed_ != job) return;
                              armed_.reset();
                              window_ = 0;
                            },
                            "batch disarm"});
}

void BatchSubsystem::NoteCompleted(const BatchResult& out) {
  for (std::size_t i = 0; i < ended_.size() && i < out.done.size(); ++i) ended_[i] = out.done[i];
}

}  // namespace urlab::world
