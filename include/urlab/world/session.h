#pragma once
// Session: one built, bound scene ready to run: the compiled model inside the PhysicsEngine, the
// ControlSystem with every articulation's controller, the articulation registry and bindings,
// and the command API (pause, resets, host-driven mocap poses). The Manager creates one per
// BeginPlay and hands it to every subsystem; a subsystem may keep the shared_ptr for as long as
// it likes (everything stays valid; the physics thread stops when the Manager ends play).
//
// Threading contract
// - Main thread: Create, Start, Stop, SyncHostPoses, SetHostDrivenPose/ClearHostDriven,
//   EditModel and ReloadKeepingState (they replace scene().spec, under a small mutex that spec()
//   takes, and compiled_options(), which only the main thread reads).
// - Any thread: engine() and controls() (under their own contracts), spec(), the registry getters
//   (immutable after Create), SetPaused, SetResetOnDivergence, ResetToInitialState,
//   ResetArticulation, FireLauncher (a round-robin counter per launcher, atomic).
// - Physics thread: the session's pre-step callback copies the host-driven poses into
//   d->mocap_pos/d->mocap_quat (a small mutex shared with SyncHostPoses, held for a copy).
#include <array>
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "urlab/control/articulation_control.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/latency.h"
#include "urlab/physics/observation_delay.h"
#include "urlab/physics/views.h"
#include "urlab/world/randomize.h"
#include "urlab/world/randomize_settings.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab::world {

class Randomizer;  // src/world/randomizer.h

// What a session needs beyond the scene file.
struct SessionOptions {
  int speed_percent = 100;  // 5..100 of real time
  bool as_fast_as_possible = false;
  bool start_paused = false;
  // Reset the simulation when it diverges (NaN/Inf, MuJoCo instability warnings): the engine
  // resets at once, then the session puts every articulation back in its initial keyframe.
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

class Session : public std::enable_shared_from_this<Session> {
 public:
  // Composes and compiles `scene`, creates the engine (not started), binds every articulation by
  // its "{name}_" prefix, builds each controller, sets the control sources and puts every
  // articulation in its initial keyframe (holding it when asked). Throws InputError /
  // CompileError for a bad scene (file:line).
  static std::shared_ptr<Session> Create(const SceneConfig& scene, SessionOptions options = {});
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  // ---- Lifecycle (main thread) ----
  // Starts the physics thread (paused when the options say so).
  void Start();
  // Stops and joins it; commands queued meanwhile are applied. Idempotent.
  void Stop();

  // ---- Registry (any thread) ----
  physics::PhysicsEngine& engine() { return *engine_; }
  const physics::PhysicsEngine& engine() const { return *engine_; }
  control::ControlSystem& controls() { return *controls_; }
  // The compiled scene (layouts, diagnostics, document); its model lives in engine(). Its spec
  // is replaced by EditModel and ReloadKeepingState: read it on the main thread, or use spec().
  const CompiledScene& scene() const { return compiled_; }
  // The scene's root spec as it is now (the one that compiled the running model's values). Any
  // thread; the spec itself is not changed once a session holds it (edits go to a copy that
  // replaces it), so the caller may write it as MJCF while the session moves on.
  std::shared_ptr<const mjSpec> spec() const;
  // The physics options as compiled from the scene (the engine's follow run-time changes).
  const mjOption& compiled_options() const { return compiled_options_; }
  const SceneConfig& scene_config() const { return config_; }
  const SessionOptions& options() const { return options_; }
  const std::vector<Articulation>& articulations() const { return articulations_; }
  // nullptr when absent.
  const Articulation* FindArticulation(std::string_view name) const;
  // Articulation owning a full (prefixed) element name, nullptr when none (longest prefix wins).
  const Articulation* OwnerOf(std::string_view full_name) const;
  // Throws Error naming the articulation when absent.
  const Articulation& Require(std::string_view name) const;
  // The scene's Quick Convert props (immutable after Create); nullptr when absent. A mocap
  // prop's body ("body") is driven with SetHostDrivenPose(prop name, "body", pose).
  const std::vector<PropLayout>& props() const { return compiled_.props; }
  const PropLayout* FindProp(std::string_view name) const;
  // The scene's impulse launchers (immutable after Create); nullptr when absent.
  const std::vector<LauncherLayout>& launchers() const { return compiled_.launchers; }
  const LauncherLayout* FindLauncher(std::string_view name) const;

  // ---- Commands (any thread) ----
  void SetPaused(bool paused) { engine_->SetPaused(paused); }
  void SetResetOnDivergence(bool on) { engine_->SetResetOnDivergence(on); }
  // Resets the whole simulation to qpos0, then every articulation to its initial keyframe, as
  // one queued command; returns its sequence number.
  std::uint64_t ResetToInitialState();
  // That initial state (without randomisation) as a function any mjData of this model can be
  // reset with: mj_resetData, then every articulation's initial keyframe. It refers to the
  // articulations' controls: use it while the session lives.
  physics::StepCallback InitialStateReset() const;
  // Resets one articulation to keyframe `key` (its initial keyframe when empty); the rest of the
  // scene is untouched. Throws Error for an unknown articulation or keyframe.
  std::uint64_t ResetArticulation(std::string_view name, std::string_view key = {});
  // Fires a launcher: its next projectile (round robin over the pool, so when all are out the
  // one fired longest ago is reused) is put at the muzzle in the launch orientation, moving at
  // the launcher's speed along its +x without spin, by one queued SetState command (recorded
  // like any other, so re-simulation stays exact). Throws Error for an unknown launcher.
  struct Launch {
    std::uint64_t seq = 0;  // the command's sequence number (engine().WaitForCommand)
    int projectile = -1;    // index in the launcher's pool
  };
  Launch FireLauncher(std::string_view name);
  Launch FireLauncher(std::size_t index);

  // ---- Emulated latency (any thread; physics/latency.h) ----
  // Sets an articulation's control and observation delays (replacing the previous ones; every
  // line restarts), drawing jitter from `seed` (the scene's seed when absent).
  // Applied under the step mutex, so it takes effect at the next step. Throws Error for an
  // unknown articulation.
  void SetLatency(std::string_view articulation, const physics::ArticulationLatency& latency,
                  std::optional<std::uint64_t> seed = std::nullopt);
  // The setting in effect (as given) and the seed it draws from.
  physics::ArticulationLatency Latency(std::string_view articulation) const;
  std::uint64_t latency_seed() const;
  // ---- Domain randomisation (any thread; world/randomize.h) ----
  // Resets to the initial state like ResetToInitialState, after drawing `config` (the scene's
  // `randomize:` when null) from `seed` into this simulation's own model (the engine's copy;
  // never the compiled original the session was built from). Without a seed the draw comes from
  // the scene's seed and the number of randomised resets so far, so a run with the same seed
  // draws the same sequence. Throws Error for a config that names unknown targets or
  // parameters. Returns the reset command's sequence number and the values drawn.
  struct RandomizedReset {
    std::uint64_t seq = 0;
    RandomDraws draws;
  };
  RandomizedReset ResetRandomized(std::optional<std::uint64_t> seed,
                                  const RandomizeConfig* config = nullptr);
  // The draws of the last randomised reset (empty before one).
  RandomDraws last_draws() const;
  // True when the scene has a `randomize:` section (every reset then draws).
  bool randomizes() const { return !RandomizeOf(config_).config.empty(); }
  // The mechanism that draws `randomize:` (null before Build), for simulations kept beside this
  // one that draw into models of their own (the environments of a batch,
  // world/batch_subsystem.h).
  std::shared_ptr<const Randomizer> randomizer() const { return randomizer_; }

  // ---- Editing the running model (main thread) ----
  // Applies `edit` to a copy of the scene's spec and compiles it; when the result has the running
  // model's structure (physics::InPlaceDifference: the same sizes, names, addresses and the
  // values URLab bound once), its values are copied into the running model in place by one
  // ReplaceModel command and the edited copy becomes the scene's spec. The state (mjData: qpos,
  // qvel, act, ctrl, mocap, time, warm start, ...) is kept exactly. The options in effect stay
  // unless the edit changed the spec's options. Throws Error saying why (the edit does not
  // compile, changes the structure, or the scene randomises its model) with nothing changed.
  // Returns the command's sequence number (engine().WaitForCommand).
  std::uint64_t EditModel(const std::function<void(mjSpec*)>& edit);
  // Reads the scene's files again (LoadSceneOrModel + the checks and build `urlab run` uses) and
  // brings the new values into the running model as EditModel does, keeping the state. Not kept
  // (nothing changed; the caller restarts the scene) when the scene file itself changed, a file
  // fails to load, the structure changed or the scene randomises its model: `reason` says which.
  struct Reload {
    bool kept = false;
    std::uint64_t seq = 0;  // the ReplaceModel command when kept
    std::string reason;     // why not, when not kept
  };
  Reload ReloadKeepingState();

  // ---- Host-driven mocap bodies (main thread) ----
  // Marks a mocap body of an articulation as driven by the host and sets its world pose; from the
  // next SyncHostPoses on, the physics thread writes it into mocap_pos/mocap_quat before every
  // step. Throws Error when the body is unknown or not a mocap body, or the pose is not finite.
  void SetHostDrivenPose(std::string_view articulation, std::string_view body, const Pose& pose);
  // Stops driving the body (it keeps its last mocap pose). False when it was not host-driven.
  bool ClearHostDriven(std::string_view articulation, std::string_view body);
  // Publishes the host's poses to the physics thread (the Manager calls it every Tick).
  void SyncHostPoses();

 private:
  struct HostPose {
    int mocap_id = -1;
    Pose pose;
  };

  explicit Session(SessionOptions options) : options_(options) {}
  void Build(const SceneConfig& scene);
  int MocapOf(std::string_view articulation, std::string_view body) const;
  void BuildRandomizer();          // Build: the randomizer's targets, checked against the scene
  void ApplyHostPoses(mjData* d);  // physics thread
  // Queues one reset restoring every articulation's initial keyframe (qpos0 first when `full`).
  // `qpos_offsets` ({qpos address, offset}) are added after the keyframes (qpos noise).
  std::uint64_t QueueInitialReset(bool full, std::vector<std::pair<int, double>> qpos_offsets = {});
  // Each articulation with an initial keyframe: its control and the keyframe's id.
  std::vector<std::pair<const control::ArticulationControl*, int>> InitialKeys() const;
  // EditModel and ReloadKeepingState: `model` (compiled from `spec`) replaces the running
  // model's values; `spec` becomes the scene's. Throws Error when the structure differs.
  std::uint64_t ReplaceModel(std::shared_ptr<mjSpec> spec, physics::Model model,
                             bool options_changed, std::string label);

  SessionOptions options_;
  SceneConfig config_;
  std::string scene_text_;         // the scene file as read by Create ("" for a single MJCF file)
  mutable std::mutex spec_mutex_;  // guards compiled_.spec (written by the main thread)
  // What a gait controller took from the model when it bound (control/gait.h: its bodies'
  // masses, inertias and poses, its geoms' poses and sizes), per articulation walking with one:
  // EditModel and ReloadKeepingState refuse a model where they differ. Immutable after Create.
  struct GaitBound {
    std::string articulation;
    std::vector<int> bodies, geoms;
    std::vector<mjtNum> values;
  };
  std::vector<GaitBound> gait_bound_;
  CompiledScene compiled_;
  mjOption compiled_options_{};
  std::unique_ptr<control::ControlSystem> controls_;
  std::unique_ptr<physics::PhysicsEngine> engine_;
  std::vector<Articulation> articulations_;
  // Per launcher: projectiles fired so far (the next one is count % pool).
  std::unique_ptr<std::atomic<std::uint64_t>[]> launches_;

  std::vector<HostPose> host_poses_;  // main thread: the host's latest poses
  bool host_dirty_ = false;           // main thread: host_poses_ changed since the last sync
  std::atomic<bool> has_host_poses_{false};
  std::mutex host_mutex_;  // guards published_poses_
  std::vector<HostPose> published_poses_;
  std::vector<HostPose> applying_;  // physics thread scratch
  // Emulated latency: the observation delay the engine's observed subscriptions pass through,
  // and the settings in effect per articulation (guarded by latency_mutex_).
  std::shared_ptr<physics::ObservationDelay> observation_delay_;
  mutable std::mutex latency_mutex_;
  std::vector<physics::ArticulationLatency> latency_;
  std::uint64_t latency_seed_ = 0;
  // Domain randomisation: the mechanism (src/world/randomizer.h), the number of randomised
  // resets so far, the last draws (guarded by randomize_mutex_).
  std::shared_ptr<const Randomizer> randomizer_;
  mutable std::mutex randomize_mutex_;
  std::uint64_t randomized_resets_ = 0;
  RandomDraws last_draws_;
};

}  // namespace urlab::world
