#include "urlab/world/session.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "urlab/control/gait.h"
#include "urlab/core/files.h"
#include "urlab/mjcf/spec.h"
#include "urlab/world/controller_factory.h"
#include "urlab/world/names.h"
#include "urlab/world/scene_checks.h"
#include "world/randomizer.h"

namespace urlab::world {

namespace {

// The values a gait controller reads once, when it binds, of `bodies` and `geoms`.
std::vector<mjtNum> GaitValues(const mjModel* m, const std::vector<int>& bodies,
                               const std::vector<int>& geoms) {
  std::vector<mjtNum> v;
  const auto add = [&v](const mjtNum* at, int n) { v.insert(v.end(), at, at + n); };
  for (int b : bodies) {
    add(m->body_pos + 3 * b, 3);
    add(m->body_quat + 4 * b, 4);
    add(m->body_ipos + 3 * b, 3);
    add(m->body_iquat + 4 * b, 4);
    add(m->body_inertia + 3 * b, 3);
    add(m->body_mass + b, 1);
    add(m->body_subtreemass + b, 1);
  }
  for (int g : geoms) {
    add(m->geom_pos + 3 * g, 3);
    add(m->geom_quat + 4 * g, 4);
    add(m->geom_size + 3 * g, 3);
  }
  return v;
}

// The state addresses an articulation's observations come from (its joints, actuators, sensors
// and bodies).
physics::ObservedSlice ObservedSliceOf(const physics::ArticulationBindings& b) {
  physics::ObservedSlice s;
  for (const physics::JointView& j : b.joints().all()) {
    for (int k = 0; k < j.qpos_size; ++k) s.qpos.push_back(j.qpos_adr + k);
    for (int k = 0; k < j.dof_size; ++k) s.dof.push_back(j.dof_adr + k);
  }
  for (const physics::ActuatorView& a : b.actuators().all()) {
    s.actuator.push_back(a.id);
    if (a.act_adr >= 0) s.act.push_back(a.act_adr);
  }
  for (const physics::SensorView& v : b.sensors().all()) {
    for (int k = 0; k < v.dim; ++k) s.sensor.push_back(v.adr + k);
  }
  for (const physics::BodyView& body : b.bodies().all()) s.body.push_back(body.id);
  return s;
}

}  // namespace

std::shared_ptr<Session> Session::Create(const SceneConfig& scene, SessionOptions options) {
  std::shared_ptr<Session> s(new Session(options));
  s->Build(scene);
  return s;
}

Session::~Session() {
  Stop();
  // The model (with its extensions) lives in the engine.
  compiled_ = CompiledScene{};
  articulations_.clear();
  engine_.reset();
  controls_.reset();
}

void Session::Build(const SceneConfig& scene) {
  config_ = scene;
  // What a reload compares: a scene file's settings beyond its models need a restart.
  if (IsSceneFile(scene.path)) {
    try {
      scene_text_ = ReadInputFile(scene.path, "scene file");
    } catch (const Error&) {
      scene_text_.clear();  // a scene given in memory: a reload finds it changed
    }
  }
  // Composes and compiles, then every check `urlab validate` runs (world/scene_checks.h).
  compiled_ = BuildCheckedScene(scene);
  for (const auto& d : compiled_.diagnostics) spdlog::warn("{}: {}", d.where.str(), d.message);

  physics::PhysicsEngine::Options eo;
  eo.speed_percent = options_.speed_percent;
  eo.as_fast_as_possible = options_.as_fast_as_possible;
  eo.reset_on_divergence = options_.reset_on_divergence;
  eo.log_events = false;  // the Manager's event log reports each event once
  compiled_options_ = compiled_.model.get()->opt;
  engine_ = std::make_unique<physics::PhysicsEngine>(std::move(compiled_.model), eo);
  controls_ = std::make_unique<control::ControlSystem>();
  controls_->SetGlobalSource(scene.control_source);

  // Bind every articulation and build its controller (the thread does not run yet).
  observation_delay_ = std::make_shared<physics::ObservationDelay>();
  engine_->WithLockedData([&](mjModel* m, mjData* d) {
    for (std::size_t i = 0; i < scene.articulations.size(); ++i) {
      const ArticulationConfig& ac = scene.articulations[i];
      Articulation a;
      a.config = ac;
      a.prefix =
          i < compiled_.articulations.size() ? compiled_.articulations[i].prefix : ac.name + "_";
      a.bindings = std::make_unique<physics::ArticulationBindings>(m, d, a.prefix);
      a.control = &controls_->Add(std::make_unique<control::ArticulationControl>(*a.bindings));
      a.control->SetSourceOverride(ac.control_source);
      InstallController(ac, *a.control, m);
      InstallTwist(ac, *a.bindings, *a.control, m);
      if (!ac.keyframe.empty()) {
        try {
          a.initial_key = FindNamed(m, mjOBJ_KEY, a.prefix, ac.keyframe);
        } catch (const Error& e) {
          throw InputError(ac.where, ac.name + ": " + e.what());
        }
        if (a.initial_key < 0) {
          throw InputError(ac.where,
                           ac.name + ": keyframe '" + ac.keyframe + "' is not in " + ac.mjcf);
        }
      }
      observation_delay_->AddGroup(ac.name, ObservedSliceOf(*a.bindings));
      articulations_.push_back(std::move(a));
    }
  });
  engine_->SetObservationDelay(observation_delay_);
  for (const Articulation& a : articulations_) {
    if (!dynamic_cast<const control::GaitController*>(a.control->controller())) continue;
    GaitBound g;
    g.articulation = a.name();
    for (const physics::BodyView& b : a.bindings->bodies().all()) g.bodies.push_back(b.id);
    for (const physics::GeomView& geom : a.bindings->geoms().all()) g.geoms.push_back(geom.id);
    g.values = GaitValues(engine_->model(), g.bodies, g.geoms);
    gait_bound_.push_back(std::move(g));
  }
  BuildRandomizer();
  latency_.resize(articulations_.size());
  latency_seed_ = scene.seed;
  launches_ = std::make_unique<std::atomic<std::uint64_t>[]>(compiled_.launchers.size());
  controls_->Install(*engine_);
  engine_->SetArticulationResolver([this](std::string_view name) {
    const Articulation* a = OwnerOf(name);
    return a ? a->name() : std::string();
  });
  engine_->AddPreStepCallback([this](const mjModel*, mjData* d) { ApplyHostPoses(d); });
  // After a divergence the engine reset the data at once; put every articulation back in its
  // initial keyframe (delivered on the main thread by whoever polls the engine's events).
  engine_->AddEventListener([this](const physics::EngineEvent& e) {
    if (e.kind == physics::EngineEventKind::kDivergence && e.auto_reset) ResetToInitialState();
  });

  // Initial keyframes (applied now: the thread is not running), then holds.
  QueueInitialReset(/*full=*/false);
  for (Articulation& a : articulations_) {
    a.control->SeedTargets(a.initial_key);
    if (a.config.hold_keyframe) a.control->HoldKeyframe(a.initial_key);
  }
  // Delays start holding the seeded targets (the command in effect now).
  for (const Articulation& a : articulations_) {
    if (a.config.latency != physics::ArticulationLatency{}) SetLatency(a.name(), a.config.latency);
  }
  if (randomizes()) ResetRandomized(std::nullopt);  // the first draw (applied at once)
  engine_->DrainEvents();                           // the initial reset is not news
}

void Session::BuildRandomizer() {
  std::vector<Randomizer::Target> targets;
  const mjModel* m = engine_->model();
  for (const Articulation& a : articulations_) {
    Randomizer::Target t;
    t.name = a.name();
    const physics::ArticulationBindings& b = *a.bindings;
    for (const physics::GeomView& g : b.geoms().all()) t.geoms.push_back(g.id);
    for (const physics::BodyView& body : b.bodies().all()) t.bodies.push_back(body.id);
    for (std::size_t i = 0; i < b.joints().size(); ++i) {
      const physics::JointView& j = b.joints().all()[i];
      for (int k = 0; k < j.dof_size; ++k) t.dofs.push_back(j.dof_adr + k);
      if (j.type == mjJNT_HINGE || j.type == mjJNT_SLIDE) {
        t.joints.emplace_back(b.joints().short_names()[i], j.qpos_adr);
      }
    }
    for (const physics::ActuatorView& act : b.actuators().all()) t.actuators.push_back(act.id);
    t.pd = dynamic_cast<control::PdController*>(a.control->controller());
    if (t.pd) {
      for (int i = 0; i < a.control->num_actuators(); ++i)
        t.nominal_gains.push_back(t.pd->gains(i));
    }
    targets.push_back(std::move(t));
  }
  for (const PropLayout& p : compiled_.props) {
    Randomizer::Target t;
    t.name = p.name;
    t.prop = true;
    if (p.body >= 0) t.bodies.push_back(p.body);
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] == p.body) t.geoms.push_back(g);
    }
    targets.push_back(std::move(t));
  }
  auto r = std::make_shared<Randomizer>(m, std::move(targets));
  const RandomizeSettings& randomize = RandomizeOf(config_);
  const std::string problem = r->Check(randomize.config);
  if (!problem.empty()) throw InputError(randomize.where, "randomize: " + problem);
  randomizer_ = std::move(r);
}

void Session::Start() {
  // Only ever pauses: a subsystem may have paused the engine in BeginPlay (lockstep).
  if (options_.start_paused) engine_->SetPaused(true);
  engine_->Start();
}

void Session::Stop() {
  if (engine_) engine_->Stop();
}

// ---------------------------------------------------------------------------------------------
// Registry

const Articulation* Session::FindArticulation(std::string_view name) const {
  for (const Articulation& a : articulations_) {
    if (a.name() == name) return &a;
  }
  return nullptr;
}

const Articulation* Session::OwnerOf(std::string_view full_name) const {
  const Articulation* best = nullptr;
  for (const Articulation& a : articulations_) {
    if (full_name.starts_with(a.prefix) && (!best || a.prefix.size() > best->prefix.size())) {
      best = &a;
    }
  }
  return best;
}

const Articulation& Session::Require(std::string_view name) const {
  const Articulation* a = FindArticulation(name);
  if (!a) throw Error("no articulation '" + std::string(name) + "' in the scene");
  return *a;
}

// ---------------------------------------------------------------------------------------------
// Commands

std::uint64_t Session::ResetToInitialState() {
  if (randomizes()) return ResetRandomized(std::nullopt).seq;
  return QueueInitialReset(/*full=*/true);
}

std::uint64_t Session::ResetArticulation(std::string_view name, std::string_view key) {
  const Articulation& a = Require(name);
  if (key.empty()) {
    if (a.initial_key < 0) {
      throw Error("ResetArticulation: '" + a.name() + "' has no initial keyframe; name one");
    }
    return controls_->RequestKeyframeReset(*engine_, a.prefix,
                                           mj_id2name(engine_->model(), mjOBJ_KEY, a.initial_key));
  }
  // Only this articulation's keyframes, by short or full name (world/names.h).
  const int id =
      RequireNamed(engine_->model(), mjOBJ_KEY, a.prefix, key, "articulation '" + a.name() + "'");
  return controls_->RequestKeyframeReset(*engine_, a.prefix,
                                         mj_id2name(engine_->model(), mjOBJ_KEY, id));
}

std::vector<std::pair<const control::ArticulationControl*, int>> Session::InitialKeys() const {
  std::vector<std::pair<const control::ArticulationControl*, int>> keys;
  for (const Articulation& a : articulations_) {
    if (a.initial_key >= 0) keys.emplace_back(a.control, a.initial_key);
  }
  return keys;
}

physics::StepCallback Session::InitialStateReset() const {
  return [keys = InitialKeys()](const mjModel* m, mjData* d) {
    mj_resetData(m, d);
    for (const auto& [control, key] : keys) control->ResetToKeyframe(m, d, key);
  };
}

std::uint64_t Session::QueueInitialReset(bool full,
                                         std::vector<std::pair<int, double>> qpos_offsets) {
  std::vector<std::pair<const control::ArticulationControl*, int>> keys = InitialKeys();
  if (!full && keys.empty() && qpos_offsets.empty()) return 0;
  return engine_->ResetWith(
      [keys = std::move(keys), full, offsets = std::move(qpos_offsets)](const mjModel* m,
                                                                        mjData* d) {
        if (full) mj_resetData(m, d);
        for (const auto& [control, key] : keys) control->ResetToKeyframe(m, d, key);
        for (const auto& [adr, v] : offsets) d->qpos[adr] += v;
      },
      full ? "reset to the initial state" : "initial keyframes");
}

// ---------------------------------------------------------------------------------------------
// Impulse launchers

const LauncherLayout* Session::FindLauncher(std::string_view name) const {
  for (const LauncherLayout& l : compiled_.launchers) {
    if (l.name == name) return &l;
  }
  return nullptr;
}

Session::Launch Session::FireLauncher(std::string_view name) {
  const LauncherLayout* l = FindLauncher(name);
  if (!l) throw Error("no launcher '" + std::string(name) + "' in the scene");
  return FireLauncher(static_cast<std::size_t>(l - compiled_.launchers.data()));
}

Session::Launch Session::FireLauncher(std::size_t index) {
  if (index >= compiled_.launchers.size()) {
    throw Error("no launcher " + std::to_string(index) + " in the scene (it has " +
                std::to_string(compiled_.launchers.size()) + ")");
  }
  const LauncherLayout& l = compiled_.launchers[index];
  Launch out;
  out.projectile =
      static_cast<int>(launches_[index].fetch_add(1, std::memory_order_relaxed) % l.bodies.size());
  const auto i = static_cast<std::size_t>(out.projectile);
  // Position and velocity in one command: no step can run between them.
  const LaunchState s = LaunchStateOf(l);
  physics::cmd::SetState set;
  set.qpos.push_back({l.qpos_adr[i], {s.qpos.begin(), s.qpos.end()}});
  set.qvel.push_back({l.qvel_adr[i], {s.qvel.begin(), s.qvel.end()}});
  out.seq = engine_->Submit(std::move(set));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Host-driven mocap bodies

const PropLayout* Session::FindProp(std::string_view name) const {
  for (const PropLayout& p : compiled_.props) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

int Session::MocapOf(std::string_view articulation, std::string_view body) const {
  if (!FindArticulation(articulation)) {
    if (const PropLayout* p = FindProp(articulation)) {
      if (body != convert::kPropBodyName) {
        throw Error("prop '" + p->name + "' has one body, '" + convert::kPropBodyName + "'");
      }
      if (p->mocap < 0) {
        throw Error("prop '" + p->name + "' is " + convert::PropModeName(p->mode) +
                    ": only a mocap prop can be driven by the host");
      }
      return p->mocap;
    }
  }
  const Articulation& a = Require(articulation);
  const physics::BodyView* v = a.bindings->bodies().Find(body);
  if (!v) {
    throw Error("articulation '" + a.name() + "' has no body '" + std::string(body) + "'");
  }
  if (v->mocap_id < 0) {
    throw Error("body '" + v->name +
                "' is not a mocap body (only mocap=\"true\" bodies can be driven by the host)");
  }
  return v->mocap_id;
}

void Session::SetHostDrivenPose(std::string_view articulation, std::string_view body,
                                const Pose& pose) {
  const int mocap = MocapOf(articulation, body);
  HostPose hp{mocap, pose};
  const double n = std::sqrt(pose.quat[0] * pose.quat[0] + pose.quat[1] * pose.quat[1] +
                             pose.quat[2] * pose.quat[2] + pose.quat[3] * pose.quat[3]);
  if (!(n > 1e-12) || !std::isfinite(n)) throw Error("SetHostDrivenPose: invalid quaternion");
  for (double& q : hp.pose.quat) q /= n;
  for (double p : pose.pos) {
    if (!std::isfinite(p)) throw Error("SetHostDrivenPose: non-finite position");
  }
  auto it = std::find_if(host_poses_.begin(), host_poses_.end(),
                         [mocap](const HostPose& h) { return h.mocap_id == mocap; });
  if (it == host_poses_.end()) {
    host_poses_.push_back(hp);
  } else {
    *it = hp;
  }
  host_dirty_ = true;
}

bool Session::ClearHostDriven(std::string_view articulation, std::string_view body) {
  const int mocap = MocapOf(articulation, body);
  auto it = std::find_if(host_poses_.begin(), host_poses_.end(),
                         [mocap](const HostPose& h) { return h.mocap_id == mocap; });
  if (it == host_poses_.end()) return false;
  host_poses_.erase(it);
  host_dirty_ = true;
  return true;
}

void Session::SyncHostPoses() {
  if (!host_dirty_) return;
  {
    std::lock_guard<std::mutex> lock(host_mutex_);
    published_poses_ = host_poses_;
  }
  has_host_poses_.store(!host_poses_.empty(), std::memory_order_release);
  host_dirty_ = false;
}

void Session::ApplyHostPoses(mjData* d) {
  if (!has_host_poses_.load(std::memory_order_acquire)) return;
  {
    std::lock_guard<std::mutex> lock(host_mutex_);
    applying_ = published_poses_;
  }
  for (const HostPose& h : applying_) {
    std::memcpy(d->mocap_pos + 3 * h.mocap_id, h.pose.pos.data(), 3 * sizeof(mjtNum));
    std::memcpy(d->mocap_quat + 4 * h.mocap_id, h.pose.quat.data(), 4 * sizeof(mjtNum));
  }
}

// ---------------------------------------------------------------------------------------------
// Emulated latency

void Session::SetLatency(std::string_view name, const physics::ArticulationLatency& latency,
                         std::optional<std::uint64_t> seed) {
  const Articulation& a = Require(name);
  for (const auto& [channel, setting] :
       {std::pair{"control", &latency.control}, std::pair{"observation", &latency.observation}}) {
    if (const std::string problem = physics::CheckLatency(*setting, engine_->timestep());
        !problem.empty()) {
      throw Error(a.name() + ".latency." + channel + ": " + problem);
    }
  }
  const auto index = static_cast<std::size_t>(&a - articulations_.data());
  const int group = observation_delay_->Find(a.name());
  std::uint64_t s = 0;
  {
    std::lock_guard<std::mutex> lock(latency_mutex_);
    if (seed) latency_seed_ = *seed;
    s = latency_seed_;
    latency_[index] = latency;
  }
  // Not under latency_mutex_: the step mutex is never taken with another lock held.
  engine_->WithLockedData([&](mjModel* m, mjData* d) {
    const double dt = m->opt.timestep;
    using physics::LatencyChannel;
    a.control->SetControlDelay(
        physics::ResolveLatency(latency.control, dt,
                                physics::LatencySeed(s, index, LatencyChannel::kControl)),
        controls_->global_source());
    observation_delay_->Configure(
        group,
        physics::ResolveLatency(latency.observation, dt,
                                physics::LatencySeed(s, index, LatencyChannel::kObservation)),
        d);
  });
}

physics::ArticulationLatency Session::Latency(std::string_view name) const {
  const Articulation& a = Require(name);
  std::lock_guard<std::mutex> lock(latency_mutex_);
  return latency_[static_cast<std::size_t>(&a - articulations_.data())];
}

std::uint64_t Session::latency_seed() const {
  std::lock_guard<std::mutex> lock(latency_mutex_);
  return latency_seed_;
}

// ---------------------------------------------------------------------------------------------
// Domain randomisation

Session::RandomizedReset Session::ResetRandomized(std::optional<std::uint64_t> seed,
                                                  const RandomizeConfig* config) {
  const RandomizeConfig& c = config ? *config : RandomizeOf(config_).config;
  if (config) {
    const std::string problem = randomizer_->Check(*config);
    if (!problem.empty()) throw Error("randomize: " + problem);
  }
  std::uint64_t s = 0;
  {
    std::lock_guard<std::mutex> lock(randomize_mutex_);
    s = seed ? *seed : Randomizer::ResetSeed(config_.seed, randomized_resets_);
    ++randomized_resets_;
  }
  Randomizer::Applied applied;
  // The model is this engine's own (moved out of the compiled scene); the physics thread reads
  // it only under the step mutex held here.
  engine_->WithLockedData([&](mjModel* m, mjData*) {
    applied = randomizer_->Apply(c, s, m);
    for (int g = 0; g < observation_delay_->num_groups(); ++g) {
      observation_delay_->SetNoise(g, 0, 0);
    }
    for (const auto& [name, stddev] : applied.obs_noise) {
      const int g = observation_delay_->Find(name);
      if (g >= 0) observation_delay_->SetNoise(g, stddev, physics::DeriveSeed(s, 1000 + g));
    }
  });
  RandomizedReset out;
  out.seq = QueueInitialReset(/*full=*/true, std::move(applied.qpos_offsets));
  out.draws = std::move(applied.draws);
  std::lock_guard<std::mutex> lock(randomize_mutex_);
  last_draws_ = out.draws;
  return out;
}

RandomDraws Session::last_draws() const {
  std::lock_guard<std::mutex> lock(randomize_mutex_);
  return last_draws_;
}

// ---------------------------------------------------------------------------------------------
// Editing the running model

namespace {

// Why a scene whose model is randomised cannot take new values in place: the randomiser (and a
// batch's environments) keep the nominal values they recorded when the scene started.
constexpr const char* kRandomizes =
    "the scene randomises its model (randomize:), whose nominal values were recorded when it "
    "started";

}  // namespace

std::uint64_t Session::ReplaceModel(std::shared_ptr<mjSpec> spec, physics::Model model,
                                    bool options_changed, std::string label) {
  // Sizes, names and the bound values never change in a running model: read here, on the main
  // thread, while the physics thread steps.
  const std::string difference = physics::InPlaceDifference(engine_->model(), model.get());
  if (!difference.empty()) throw Error("the structure changed: " + difference);
  for (const GaitBound& g : gait_bound_) {
    if (GaitValues(model.get(), g.bodies, g.geoms) != g.values) {
      throw Error("articulation '" + g.articulation +
                  "' walks with a gait controller, which took its bodies' masses and poses and "
                  "its feet when the scene started, and they changed");
    }
  }
  const mjOption options = model->opt;
  physics::cmd::ReplaceModel c;
  c.model = std::make_shared<const physics::Model>(std::move(model));
  c.keep_options = !options_changed;
  c.label = std::move(label);
  const std::uint64_t seq = engine_->Submit(std::move(c));
  {
    std::lock_guard<std::mutex> lock(spec_mutex_);
    compiled_.spec = std::move(spec);
  }
  if (options_changed) compiled_options_ = options;
  return seq;
}

std::shared_ptr<const mjSpec> Session::spec() const {
  std::lock_guard<std::mutex> lock(spec_mutex_);
  return compiled_.spec;
}

std::uint64_t Session::EditModel(const std::function<void(mjSpec*)>& edit) {
  if (!edit) throw Error("EditModel: empty edit function");
  if (randomizes()) throw Error(std::string("EditModel: ") + kRandomizes);
  // The edit goes to a copy: the scene's spec stays as it is unless the result can replace the
  // running model.
  std::shared_ptr<mjSpec> copy(mj_copySpec(compiled_.spec.get()), mjcf::SpecDeleter());
  if (!copy) throw Error("EditModel: MuJoCo could not copy the scene's spec");
  const mjOption before = copy->option;
  edit(copy.get());
  physics::ModelPtr compiled(mj_compile(copy.get(), nullptr));
  if (!compiled) {
    throw Error(std::string("EditModel: the edited scene does not compile: ") +
                mjs_getError(copy.get()));
  }
  const bool options_changed = std::memcmp(&before, &copy->option, sizeof(mjOption)) != 0;
  try {
    return ReplaceModel(std::move(copy), physics::Model(std::move(compiled)), options_changed,
                        "edit the model");
  } catch (const Error& e) {
    throw Error(std::string("EditModel: ") + e.what() +
                "; the running model and its state are unchanged");
  }
}

Session::Reload Session::ReloadKeepingState() {
  Reload r;
  if (randomizes()) {
    r.reason = kRandomizes;
    return r;
  }
  if (IsSceneFile(config_.path)) {
    std::string text;
    try {
      text = ReadInputFile(config_.path, "scene file");
    } catch (const Error& e) {
      r.reason = e.what();
      return r;
    }
    if (text != scene_text_) {
      r.reason = "the scene file " + config_.path + " changed (its settings apply at a restart)";
      return r;
    }
  }
  CompiledScene fresh;
  try {
    // The same path `urlab run` builds a scene from: the files, then every check.
    fresh = BuildCheckedScene(LoadSceneOrModel(config_.path));
  } catch (const std::exception& e) {
    r.reason = e.what();
    return r;
  }
  for (const auto& d : fresh.diagnostics) spdlog::warn("{}: {}", d.where.str(), d.message);
  const bool options_changed =
      std::memcmp(&fresh.spec->option, &compiled_.spec->option, sizeof(mjOption)) != 0;
  try {
    r.seq =
        ReplaceModel(fresh.spec, std::move(fresh.model), options_changed, "reload " + config_.path);
  } catch (const Error& e) {
    r.reason = e.what();
    return r;
  }
  compiled_.diagnostics = std::move(fresh.diagnostics);
  r.kept = true;
  return r;
}

}  // namespace urlab::world
