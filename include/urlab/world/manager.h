#pragma once
// Manager: the thin coordinator of one running world (the description's AAMjManager). It owns
// the lifecycle: BeginPlay creates a Session (the built, bound scene with its engine, controls
// and command API), begins every subsystem in the order they were added, and starts the physics
// thread; Tick delivers engine events and runs the subsystems' tick phases; EndPlay ends the
// subsystems in reverse order, then stops the physics thread and releases the session. Engine
// events are logged by an EventLog listener (rate-limited), then given to the subsystems and to
// the manager's listeners.
//
// Threading contract
// - Main thread (the host's game thread): construction, AddSubsystem, BeginPlay, Tick, EndPlay,
//   the destructor, AddEventListener, frame() and BodyPose(). Subsystem hooks and event
//   listeners run on the main thread, inside BeginPlay/Tick/EndPlay.
// - Any thread, while playing: session() and what it offers under its own contract.
// - Several Managers may play in one process (a training and an evaluation batch): each has
//   its own session, engine and thread; nothing of MuJoCo's process-wide state (its error
//   handlers, the engine plugins: core/mujoco_handlers.h) belongs to one of them.
// - A MuJoCo error while playing never ends the process: the engine pauses and reports it, and
//   Tick delivers the report to the log, the subsystems and the listeners.
#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/physics/engine.h"
#include "urlab/world/event_log.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"
#include "urlab/world/subsystem.h"

namespace urlab::world {

// What the manager needs beyond the scene file.
using ManagerOptions = SessionOptions;

class Manager {
 public:
  using EventListener = std::function<void(const physics::EngineEvent&)>;

  explicit Manager(ManagerOptions options = {});
  ~Manager();  // EndPlay.
  Manager(const Manager&) = delete;
  Manager& operator=(const Manager&) = delete;

  // ---- Subsystems (main thread) ----
  // Adds a subsystem; they begin in the order added and end in reverse. Not while playing.
  // Returns it. Throws Error for a second subsystem of the same name.
  Subsystem& AddSubsystem(std::unique_ptr<Subsystem> subsystem);
  // nullptr when none has that name.
  Subsystem* FindSubsystem(std::string_view name) const;
  const std::vector<std::unique_ptr<Subsystem>>& subsystems() const { return subsystems_; }

  // ---- Lifecycle (main thread) ----
  // Builds the session, begins the subsystems, starts the physics thread. Throws InputError /
  // CompileError for a bad scene (file:line), Error when this manager already plays or another
  // one does, or what a subsystem's BeginPlay throws. On failure nothing is left running.
  void BeginPlay(const SceneConfig& scene);
  // Delivers engine events (log, subsystems, listeners), runs the subsystems' kInput phase,
  // publishes host-driven poses, runs kUpdate, takes the newest state frame, runs kPresent.
  // Returns the number of engine events delivered. No-op when not playing.
  int Tick();
  // Ends the subsystems (reverse order), stops the physics thread, delivers the last events and
  // releases the session (subsystems holding it keep it alive, stopped). Idempotent.
  void EndPlay();
  bool playing() const { return session_ != nullptr; }
  // True when a subsystem asks to end play (Subsystem::RequestsStop). Main thread.
  bool StopRequested() const;

  // ---- The running world (valid while playing) ----
  Session& session();
  std::shared_ptr<Session> shared_session() const { return session_; }

  // ---- Events (main thread) ----
  // Called inside Tick (and EndPlay, for the last events) for every engine event, after the
  // event log and the subsystems. EndPlay removes the listeners.
  void AddEventListener(EventListener fn);

  // ---- Transform sync (main thread) ----
  // The state frame taken by the last Tick (the newest published); nullptr before.
  const physics::StateFrame* frame() const { return frame_; }
  // The pose of a body from frame(); std::nullopt when unknown or before the first Tick.
  std::optional<Pose> BodyPose(std::string_view articulation, std::string_view body) const;
  std::optional<Pose> BodyPose(int body_id) const;

 private:
  void OnEvent(const physics::EngineEvent& e);
  // Ends the begun subsystems in reverse order, logging (not throwing) their failures.
  void EndSubsystems();
  void RunPhase(TickPhase phase);

  ManagerOptions options_;
  std::vector<std::unique_ptr<Subsystem>> subsystems_;
  std::size_t begun_ = 0;  // subsystems_[0, begun_) have begun play
  std::shared_ptr<Session> session_;
  std::shared_ptr<physics::StateSubscription> state_;  // the manager's own state reader
  std::unique_ptr<EventLog> event_log_;
  std::vector<EventListener> listeners_;
  const physics::StateFrame* frame_ = nullptr;
};

}  // namespace urlab::world
