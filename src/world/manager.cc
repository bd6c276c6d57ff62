#include "urlab/world/manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <utility>

#include "urlab/world/controller_factory.h"
#include "urlab/world/scene_checks.h"

namespace urlab::world {

std::atomic<Manager*> Manager::playing_{nullptr};

Manager::Manager(ManagerOptions options) : options_(options) {}

Manager::~Manager() { EndPlay(); }

// ---------------------------------------------------------------------------------------------
// Lifecycle

void Manager::BeginPlay(const SceneConfig& scene) {
  if (playing()) throw Error("Manager::BeginPlay: this manager is already playing");
  Manager* expected = nullptr;
  if (!playing_.compare_exchange_strong(expected, this)) {
    throw Error(
        "Manager::BeginPlay: only one manager per world: another Manager is already playing "
        "(EndPlay it first)");
  }
  try {
    Build(scene);
  } catch (...) {
    EndPlay();
    throw;
  }
}

void Manager::Build(const SceneConfig& scene) {
  config_ = scene;
  // Composes and compiles, then every check `urlab validate` runs (world/scene_checks.h).
  compiled_ = BuildCheckedScene(scene);
  for (const auto& d : compiled_.diagnostics) spdlog::warn("{}: {}", d.where.str(), d.message);

  physics::PhysicsEngine::Options eo;
  eo.speed_percent = options_.speed_percent;
  eo.as_fast_as_possible = options_.as_fast_as_possible;
  eo.reset_on_divergence = options_.reset_on_divergence;
  eo.log_events = false;  // Tick() logs each event it delivers
  engine_ = std::make_unique<physics::PhysicsEngine>(std::move(compiled_.model), eo);
  controls_ = std::make_unique<control::ControlSystem>();
  controls_->SetGlobalSource(scene.control_source);

  // Bind every articulation and build its controller (the thread does not run yet).
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
      if (!ac.keyframe.empty()) {
        a.initial_key = mj_name2id(m, mjOBJ_KEY, (a.prefix + ac.keyframe).c_str());
        if (a.initial_key < 0) {
          throw InputError(ac.where,
                           ac.name + ": keyframe '" + ac.keyframe + "' is not in " + ac.mjcf);
        }
      }
      articulations_.push_back(std::move(a));
    }
  });
  controls_->Install(*engine_);
  engine_->SetArticulationResolver([this](std::string_view name) {
    const Articulation* a = OwnerOf(name);
    return a ? a->name() : std::string();
  });
  engine_->AddEventListener([this](const physics::EngineEvent& e) { OnEvent(e); });
  engine_->AddPreStepCallback([this](const mjModel*, mjData* d) { ApplyHostPoses(d); });

  // Initial keyframes (applied now: the thread is not running), then holds.
  QueueInitialReset(/*full=*/false);
  for (Articulation& a : articulations_) {
    if (a.config.hold_keyframe) a.control->HoldKeyframe(a.initial_key);
  }
  engine_->DrainEvents();  // the initial reset is not news

  for (Subsystem* s : {debug_.get(), network_.get(), input_.get()}) {
    if (s) s->BeginPlay(*this);
  }
  engine_->SetPaused(options_.start_paused);
  engine_->Start();
  spdlog::info("playing {} ({} articulation(s), nq={}, nu={}, timestep={} s)", scene.path,
               articulations_.size(), engine_->model()->nq, engine_->model()->nu,
               engine_->model()->opt.timestep);
}

void Manager::EndPlay() {
  if (engine_) {
    engine_->Stop();
    for (Subsystem* s : {debug_.get(), network_.get(), input_.get()}) {
      if (s) s->EndPlay(*this);
    }
    try {
      engine_->PollEvents();  // the last reports still reach the log and the listeners
    } catch (const std::exception& e) {
      spdlog::error("Manager::EndPlay: an event listener failed: {}", e.what());
    }
  }
  frame_ = nullptr;
  listeners_.clear();
  quiet_divergences_ = 0;
  // What the compiled scene keeps registered against the model (software sensors) goes first:
  // the model itself lives in the engine.
  compiled_ = CompiledScene{};
  articulations_.clear();
  engine_.reset();
  controls_.reset();
  host_poses_.clear();
  {
    std::lock_guard<std::mutex> lock(host_mutex_);
    published_poses_.clear();
  }
  has_host_poses_.store(false);
  Manager* self = this;
  playing_.compare_exchange_strong(self, nullptr);
}

int Manager::Tick() {
  if (!engine_) return 0;
  const int events = engine_->PollEvents();
  for (Subsystem* s : {debug_.get(), network_.get(), input_.get()}) {
    if (s) s->Tick(*this);
  }
  if (host_dirty_) {
    {
      std::lock_guard<std::mutex> lock(host_mutex_);
      published_poses_ = host_poses_;
    }
    has_host_poses_.store(!host_poses_.empty(), std::memory_order_release);
    host_dirty_ = false;
  }
  frame_ = engine_->LatestRenderSnapshot();
  return events;
}

// ---------------------------------------------------------------------------------------------
// Accessors and commands

physics::PhysicsEngine& Manager::engine() {
  if (!engine_) throw Error("Manager: not playing (call BeginPlay first)");
  return *engine_;
}

control::ControlSystem& Manager::controls() {
  if (!controls_) throw Error("Manager: not playing (call BeginPlay first)");
  return *controls_;
}

const Articulation* Manager::FindArticulation(std::string_view name) const {
  for (const Articulation& a : articulations_) {
    if (a.name() == name) return &a;
  }
  return nullptr;
}

const Articulation* Manager::OwnerOf(std::string_view full_name) const {
  const Articulation* best = nullptr;
  for (const Articulation& a : articulations_) {
    if (full_name.starts_with(a.prefix) && (!best || a.prefix.size() > best->prefix.size())) {
      best = &a;
    }
  }
  return best;
}

const Articulation& Manager::Require(std::string_view name) const {
  const Articulation* a = FindArticulation(name);
  if (!a) throw Error("Manager: no articulation '" + std::string(name) + "' in the scene");
  return *a;
}

void Manager::AddEventListener(EventListener fn) {
  if (!fn) throw Error("Manager::AddEventListener: empty listener");
  listeners_.push_back(std::move(fn));
}

void Manager::SetPaused(bool paused) { engine().SetPaused(paused); }

void Manager::SetResetOnDivergence(bool on) { engine().SetResetOnDivergence(on); }

void Manager::ResetToInitialState() {
  engine();  // throws when not playing
  QueueInitialReset(/*full=*/true);
}

void Manager::ResetArticulation(std::string_view name, std::string_view key) {
  const Articulation& a = Require(name);
  if (key.empty()) {
    if (a.initial_key < 0) {
      throw Error("Manager::ResetArticulation: '" + a.name() +
                  "' has no initial keyframe; name one");
    }
    controls().RequestKeyframeReset(engine(), a.prefix, a.prefix + a.config.keyframe);
    return;
  }
  // Only this articulation's keyframes: "{prefix}{key}".
  controls().RequestKeyframeReset(engine(), a.prefix, a.prefix + std::string(key));
}

void Manager::QueueInitialReset(bool full) {
  std::vector<std::pair<const control::ArticulationControl*, int>> keys;
  for (const Articulation& a : articulations_) {
    if (a.initial_key >= 0) keys.emplace_back(a.control, a.initial_key);
  }
  if (!full && keys.empty()) return;
  engine_->ResetWith(
      [keys = std::move(keys), full](const mjModel* m, mjData* d) {
        if (full) mj_resetData(m, d);
        for (const auto& [control, key] : keys) control->ResetToKeyframe(m, d, key);
      },
      full ? "reset to the initial state" : "initial keyframes");
}

// ---------------------------------------------------------------------------------------------
// Events

void Manager::OnEvent(const physics::EngineEvent& e) {
  using physics::EngineEventKind;
  switch (e.kind) {
    case EngineEventKind::kReset:
    case EngineEventKind::kRestored:
      spdlog::info("physics: {} (at t={:.4f} s)", e.message, e.sim_time);
      break;
    case EngineEventKind::kDivergence: {
      // A model that keeps blowing up reports every episode: log at most once a second.
      const auto now = std::chrono::steady_clock::now();
      if (now - last_divergence_log_ >= std::chrono::seconds(1)) {
        spdlog::warn("physics: {} in articulation '{}', joint '{}'{}{}", e.message,
                     e.articulation.empty() ? "?" : e.articulation,
                     e.joint_name.empty() ? "?" : e.joint_name,
                     e.auto_reset ? "; reset to the initial state" : "",
                     quiet_divergences_
                         ? fmt::format(" ({} more since the last report)", quiet_divergences_)
                         : std::string());
        last_divergence_log_ = now;
        quiet_divergences_ = 0;
      } else {
        ++quiet_divergences_;
      }
      if (e.auto_reset) QueueInitialReset(/*full=*/true);
      break;
    }
    case EngineEventKind::kError:
      spdlog::warn("physics: simulation paused at t={:.4f} s after an error; unpause to go on",
                   e.sim_time);
      break;
  }
  for (const EventListener& fn : listeners_) fn(e);
}

// ---------------------------------------------------------------------------------------------
// Transform sync

int Manager::MocapOf(std::string_view articulation, std::string_view body) const {
  const Articulation& a = Require(articulation);
  const physics::BodyView* v = a.bindings->bodies().Find(body);
  if (!v) {
    throw Error("Manager: articulation '" + a.name() + "' has no body '" + std::string(body) + "'");
  }
  if (v->mocap_id < 0) {
    throw Error("Manager: body '" + v->name +
                "' is not a mocap body (only mocap=\"true\" bodies can be driven by the host)");
  }
  return v->mocap_id;
}

void Manager::SetHostDrivenPose(std::string_view articulation, std::string_view body,
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

bool Manager::ClearHostDriven(std::string_view articulation, std::string_view body) {
  const int mocap = MocapOf(articulation, body);
  auto it = std::find_if(host_poses_.begin(), host_poses_.end(),
                         [mocap](const HostPose& h) { return h.mocap_id == mocap; });
  if (it == host_poses_.end()) return false;
  host_poses_.erase(it);
  host_dirty_ = true;
  return true;
}

void Manager::ApplyHostPoses(mjData* d) {
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

std::optional<Pose> Manager::BodyPose(int body_id) const {
  if (!frame_ || !engine_ || body_id < 0 || body_id >= engine_->model()->nbody) {
    return std::nullopt;
  }
  const auto i = static_cast<std::size_t>(body_id);
  Pose p;
  std::copy_n(frame_->xpos.begin() + static_cast<std::ptrdiff_t>(3 * i), 3, p.pos.begin());
  std::copy_n(frame_->xquat.begin() + static_cast<std::ptrdiff_t>(4 * i), 4, p.quat.begin());
  return p;
}

std::optional<Pose> Manager::BodyPose(std::string_view articulation, std::string_view body) const {
  const Articulation* a = FindArticulation(articulation);
  if (!a) return std::nullopt;
  const physics::BodyView* v = a->bindings->bodies().Find(body);
  return v ? BodyPose(v->id) : std::nullopt;
}

}  // namespace urlab::world
