#pragma once
// Manager: the thin coordinator of one running world (the description's AAMjManager). It owns the
// PhysicsEngine and the ControlSystem, plus slots for the debug, network and input subsystems
// that later work fills in. BeginPlay composes and compiles a scene, binds every articulation by
// its "{name}_" prefix, builds each articulation's controller, puts every articulation in its
// initial keyframe (holding it when asked), registers callbacks and starts the physics thread.
// Tick runs on the main thread at frame rate; EndPlay stops and releases everything.
//
// Threading contract
// - Main thread (the host's game thread): construction, the subsystem setters, BeginPlay, Tick,
//   EndPlay, the destructor, AddEventListener, SetHostDrivenPose/ClearHostDriven, frame() and
//   BodyPose(). Event listeners run on the main thread, inside Tick.
// - Any thread, while playing: engine() and controls() (under their own contracts),
//   SetPaused, ResetToInitialState, ResetArticulation, SetResetOnDivergence.
// - Physics thread: the manager's pre-step callback copying host-driven poses into
//   d->mocap_pos/d->mocap_quat (a small mutex shared with Tick, held for a copy of a few poses).
// - At most one Manager plays at a time in a process: another one's BeginPlay throws Error.
// - A MuJoCo error while playing never ends the process: the engine pauses and reports it, and
//   Tick delivers the report to the log and the listeners.
#include <array>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/control/controller.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/views.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

class Manager;

// A subsystem slot (debug visualiser, network, input): hooks called by the manager. Main thread.
class Subsystem {
 public:
  virtual ~Subsystem() = default;
  // After compile and binding, before the physics thread starts: register step callbacks here.
  virtual void BeginPlay(Manager& manager) = 0;
  // Every Tick, after engine events were delivered and before the transform sync.
  virtual void Tick(Manager& /*manager*/) {}
  // After the physics thread stopped, before the engine is released.
  virtual void EndPlay(Manager& /*manager*/) {}
};

// What the manager needs beyond the scene file.
struct ManagerOptions {
  int speed_percent = 100;  // 5..100 of real time
  bool as_fast_as_possible = false;
  bool start_paused = false;
  // Reset the simulation when it diverges (NaN/Inf, MuJoCo instability warnings): the engine
  // resets at once, then the manager puts every articulation back in its initial keyframe.
  bool reset_on_divergence = false;
};

// A world-space pose (MuJoCo frame: metres, quaternion w x y z).
struct Pose {
  std::array<double, 3> pos = {0, 0, 0};
  std::array<double, 4> quat = {1, 0, 0, 0};
};

// One articulation of the running scene.
struct Articulation {
  ArticulationConfig config;
  std::string prefix;                                       // "{name}_"
  std::unique_ptr<physics::ArticulationBindings> bindings;  // views into the engine's model/data
  control::ArticulationControl* control = nullptr;          // owned by the ControlSystem
  int initial_key = -1;                                     // scene keyframe id, -1 when none

  const std::string& name() const { return config.name; }
};

class Manager {
 public:
  using EventListener = std::function<void(const physics::EngineEvent&)>;

  explicit Manager(ManagerOptions options = {});
  ~Manager();  // EndPlay.
  Manager(const Manager&) = delete;
  Manager& operator=(const Manager&) = delete;

  // ---- Subsystem slots (main thread, before BeginPlay) ----
  void SetDebugVisualizer(std::unique_ptr<Subsystem> s) { debug_ = std::move(s); }
  void SetNetwork(std::unique_ptr<Subsystem> s) { network_ = std::move(s); }
  void SetInputHandler(std::unique_ptr<Subsystem> s) { input_ = std::move(s); }
  Subsystem* debug_visualizer() const { return debug_.get(); }
  Subsystem* network() const { return network_.get(); }
  Subsystem* input_handler() const { return input_.get(); }

  // ---- Lifecycle (main thread) ----
  // Builds and starts the scene (see the file comment). Throws InputError / CompileError for a
  // bad scene (file:line), Error when this manager already plays or another one does. On failure
  // nothing is left running.
  void BeginPlay(const SceneConfig& scene);
  // Delivers engine events, ticks the subsystems, publishes host-driven poses and takes the
  // newest render snapshot. Returns the number of engine events delivered. No-op when not
  // playing.
  int Tick();
  // Stops and joins the physics thread, delivers the last events and releases everything.
  // Idempotent.
  void EndPlay();
  bool playing() const { return engine_ != nullptr; }

  // ---- Subsystems and articulations (valid while playing) ----
  physics::PhysicsEngine& engine();
  control::ControlSystem& controls();
  // The compiled scene (layouts, diagnostics, XML); its model has moved into engine().
  const CompiledScene& scene() const { return compiled_; }
  const SceneConfig& scene_config() const { return config_; }
  const std::vector<Articulation>& articulations() const { return articulations_; }
  // nullptr when absent.
  const Articulation* FindArticulation(std::string_view name) const;
  // Articulation owning a full (prefixed) element name, nullptr when none (longest prefix wins).
  const Articulation* OwnerOf(std::string_view full_name) const;

  // ---- Events (main thread) ----
  // Called inside Tick (and EndPlay, for the last events) for every engine event, after the
  // manager logged it. EndPlay removes the listeners.
  void AddEventListener(EventListener fn);

  // ---- Simulation commands (any thread, while playing) ----
  void SetPaused(bool paused);
  void SetResetOnDivergence(bool on);
  // Resets the whole simulation to qpos0, then every articulation to its initial keyframe.
  void ResetToInitialState();
  // Resets one articulation to keyframe `key` (its initial keyframe when empty); the rest of
  // the scene is untouched. Throws Error for an unknown articulation or keyframe.
  void ResetArticulation(std::string_view name, std::string_view key = {});

  // ---- Transform sync (main thread) ----
  // Marks a mocap body of an articulation as driven by the host and sets its world pose; from
  // the next Tick on, the physics thread writes it into mocap_pos/mocap_quat before every step.
  // Throws Error when the body is unknown or not a mocap body.
  void SetHostDrivenPose(std::string_view articulation, std::string_view body, const Pose& pose);
  // Stops driving the body (it keeps its last mocap pose). False when it was not host-driven.
  bool ClearHostDriven(std::string_view articulation, std::string_view body);
  // The render snapshot taken by the last Tick (poses after the newest step); nullptr before.
  const physics::RenderSnapshot* frame() const { return frame_; }
  // The pose of a body from frame(); std::nullopt when unknown or before the first Tick.
  std::optional<Pose> BodyPose(std::string_view articulation, std::string_view body) const;
  std::optional<Pose> BodyPose(int body_id) const;

 private:
  struct HostPose {
    int mocap_id = -1;
    Pose pose;
  };

  void Build(const SceneConfig& scene);
  void OnEvent(const physics::EngineEvent& e);
  const Articulation& Require(std::string_view name) const;
  int MocapOf(std::string_view articulation, std::string_view body) const;
  // Physics thread: copies the published host poses into mjData.
  void ApplyHostPoses(mjData* d);
  // Queues one reset that restores every articulation's initial keyframe (and qpos0 first when
  // `full`).
  void QueueInitialReset(bool full);

  ManagerOptions options_;
  std::unique_ptr<Subsystem> debug_, network_, input_;

  SceneConfig config_;
  CompiledScene compiled_;
  std::unique_ptr<control::ControlSystem> controls_;
  std::unique_ptr<physics::PhysicsEngine> engine_;
  std::vector<Articulation> articulations_;
  std::vector<EventListener> listeners_;
  std::chrono::steady_clock::time_point last_divergence_log_{};
  int quiet_divergences_ = 0;  // divergences not logged since the last report
  const physics::RenderSnapshot* frame_ = nullptr;

  std::vector<HostPose> host_poses_;  // main thread: the host's latest poses
  bool host_dirty_ = false;           // main thread: host_poses_ changed since the last Tick
  std::atomic<bool> has_host_poses_{false};
  std::mutex host_mutex_;  // guards published_poses_
  std::vector<HostPose> published_poses_;
  std::vector<HostPose> applying_;  // physics thread scratch

  static std::atomic<Manager*> playing_;
};

}  // namespace urlab::world
