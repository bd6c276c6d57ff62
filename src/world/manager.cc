#include "urlab/world/manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <utility>

namespace urlab::world {

Manager::Manager(ManagerOptions options) : options_(options) {}

Manager::~Manager() { EndPlay(); }

// ---------------------------------------------------------------------------------------------
// Subsystems

Subsystem& Manager::AddSubsystem(std::unique_ptr<Subsystem> subsystem) {
  if (!subsystem) throw Error("Manager::AddSubsystem: null subsystem");
  if (playing()) throw Error("Manager::AddSubsystem: add subsystems before BeginPlay");
  if (FindSubsystem(subsystem->name())) {
    throw Error("Manager::AddSubsystem: a subsystem named '" + std::string(subsystem->name()) +
                "' was already added");
  }
  subsystems_.push_back(std::move(subsystem));
  return *subsystems_.back();
}

Subsystem* Manager::FindSubsystem(std::string_view name) const {
  for (const auto& s : subsystems_) {
    if (s->name() == name) return s.get();
  }
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Lifecycle

void Manager::BeginPlay(const SceneConfig& scene) {
  if (playing()) throw Error("Manager::BeginPlay: this manager is already playing");
  try {
    session_ = Session::Create(scene, options_);
    physics::PhysicsEngine& engine = session_->engine();
    event_log_ = std::make_unique<EventLog>();
    engine.AddEventListener([this](const physics::EngineEvent& e) { OnEvent(e); });
    state_ = engine.SubscribeState("manager");
    for (begun_ = 0; begun_ < subsystems_.size(); ++begun_) {
      subsystems_[begun_]->BeginPlay(*session_);
    }
    session_->Start();
  } catch (...) {
    EndPlay();
    throw;
  }
  const mjModel* m = session_->engine().model();
  spdlog::info("playing {} ({} articulation(s), nq={}, nu={}, timestep={} s{})", scene.path,
               session_->articulations().size(), m->nq, m->nu, session_->engine().timestep(),
               subsystems_.empty() ? "" : fmt::format(", {} subsystem(s)", subsystems_.size()));
}

void Manager::EndSubsystems() {
  for (std::size_t i = begun_; i-- > 0;) {
    try {
      subsystems_[i]->EndPlay(*session_);
    } catch (const std::exception& e) {
      spdlog::error("subsystem '{}' failed to end: {}", subsystems_[i]->name(), e.what());
    }
  }
  begun_ = 0;
}

void Manager::EndPlay() {
  if (session_) {
    EndSubsystems();  // while the physics thread still runs
    session_->Stop();
    try {
      session_->engine().PollEvents();  // the last reports still reach the log and listeners
    } catch (const std::exception& e) {
      spdlog::error("Manager::EndPlay: an event listener failed: {}", e.what());
    }
    if (event_log_) event_log_->Flush();
  }
  frame_ = nullptr;
  state_.reset();
  listeners_.clear();
  event_log_.reset();
  session_.reset();
}

void Manager::RunPhase(TickPhase phase) {
  for (const auto& s : subsystems_) s->Tick(*session_, phase);
}

int Manager::Tick() {
  if (!session_) return 0;
  const int events = session_->engine().PollEvents();
  RunPhase(TickPhase::kInput);
  session_->SyncHostPoses();
  RunPhase(TickPhase::kUpdate);
  frame_ = state_->Latest();
  RunPhase(TickPhase::kPresent);
  return events;
}

bool Manager::StopRequested() const {
  if (!session_) return false;
  return std::any_of(subsystems_.begin(), subsystems_.end(),
                     [](const auto& s) { return s->RequestsStop(); });
}

Session& Manager::session() {
  if (!session_) throw Error("Manager: not playing (call BeginPlay first)");
  return *session_;
}

// ---------------------------------------------------------------------------------------------
// Events

void Manager::AddEventListener(EventListener fn) {
  if (!fn) throw Error("Manager::AddEventListener: empty listener");
  listeners_.push_back(std::move(fn));
}

void Manager::OnEvent(const physics::EngineEvent& e) {
  event_log_->OnEvent(e);
  for (const auto& s : subsystems_) s->OnEngineEvent(*session_, e);
  for (const EventListener& fn : listeners_) fn(e);
}

// ---------------------------------------------------------------------------------------------
// Transform sync

std::optional<Pose> Manager::BodyPose(int body_id) const {
  if (!frame_ || !session_ || body_id < 0 || body_id >= session_->engine().model()->nbody) {
    return std::nullopt;
  }
  const auto i = static_cast<std::ptrdiff_t>(body_id);
  Pose p;
  std::copy_n(frame_->xpos.begin() + 3 * i, 3, p.pos.begin());
  std::copy_n(frame_->xquat.begin() + 4 * i, 4, p.quat.begin());
  return p;
}

std::optional<Pose> Manager::BodyPose(std::string_view articulation, std::string_view body) const {
  if (!session_) return std::nullopt;
  const Articulation* a = session_->FindArticulation(articulation);
  if (!a) {
    // A prop reports the pose of its one body (a dynamic prop's is simulated).
    const PropLayout* p = session_->FindProp(articulation);
    return p && body == convert::kPropBodyName ? BodyPose(p->body) : std::nullopt;
  }
  const physics::BodyView* v = a->bindings->bodies().Find(body);
  return v ? BodyPose(v->id) : std::nullopt;
}

}  // namespace urlab::world
