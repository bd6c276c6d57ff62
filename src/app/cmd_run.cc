// `urlab run`: the headless main job. Plays a scene with the Manager, ticking it at ~60 Hz on the
// main thread, logs the real-time factor and step rate once a second and stops cleanly on
// Ctrl-C / SIGTERM / SIGHUP (exit 128+signal) or after --duration (exit 0). A MuJoCo error or a
// divergence (NaN/Inf, MuJoCo's instability warnings) while playing stops it with the message and
// a hint (exit 1) unless --reset-on-divergence: after a divergence MuJoCo has already reset the
// state to qpos0 behind the controllers' back, so going on would run a different experiment
// than the one asked for.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <thread>
#include <vector>

#include "app/commands.h"
#include "app/run_network.h"
#include "app/signals.h"
#include "app/validators.h"
#include "urlab/camera/camera_subsystem.h"
#include "urlab/camera/video_recorder.h"
#include "urlab/core/files.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/core/mujoco_hints.h"
#include "urlab/net/network.h"
#include "urlab/ops/simulation.h"
#include "urlab/replay/playback.h"
#include "urlab/replay/recorder.h"
#include "urlab/viewer/viewer.h"
#include "urlab/world/batch_subsystem.h"
#include "urlab/world/manager.h"
#include "world/realtime_watch.h"

namespace urlab::app {

namespace {

using Clock = std::chrono::steady_clock;

constexpr auto kFrame = std::chrono::microseconds(16667);  // ~60 Hz main-thread tick
constexpr auto kLogPeriod = std::chrono::seconds(1);

struct RunArgs {
  std::string scene;
  double duration = 0;  // simulated seconds (exactly round(D / timestep) steps), 0: until a signal
  int speed = 100;
  bool max_speed = false;
  bool paused = false;
  bool reset_on_divergence = false;
  bool no_network = false;
  std::string files_dir;              // --files-dir: replaces the scene's network.files_dir
  std::optional<std::uint64_t> seed;  // --seed: replaces the scene's seed
  std::string ports = "scene";        // --ports: scene | auto
  int port_base = 0;                  // --port-base N (0: the scene's ports)
  std::string announce;               // --announce FILE: the bound endpoints as JSON
  std::string instance;               // --instance ID ("" : host:pid)
  bool allow_no_network = false;
  std::string step_mode;  // --step-mode: replaces the scene's network.step_mode
  // --envs N (0: not given, one environment) and the batch's options (world/batch_subsystem.h).
  int envs = 0;
  int threads = 0;
  bool no_auto_reset = false;
  int max_episode_steps = 0;
  double reset_noise = 0;
  bool raw_actions = false;
  int record_env = 0;  // --record-env I: the environment the engine runs (recorded, shown)
  bool no_cameras = false;
  std::vector<std::string> video;  // --video CAM OUT: a camera's frames to MP4/WebM
  // `urlab record` (and `run --record`): the file to record to, and how.
  std::string record;
  bool no_compress = false;
  bool sensordata = false;
  double ring_seconds = 0;
  double keyframe_interval = 1;
  // `urlab view` (and `run --view`): the window.
  bool view = false;
  viewer::ViewerOptions viewer;
};

// What is at an output whose writer failed, for the message.
std::string WhatIsThere(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return "nothing was kept at " + path;
  return fmt::format("{} holds the {} bytes written (it may not play)", path,
                     std::filesystem::file_size(path, ec));
}

// "message" plus MuJoCo's hint on a second line when the hint table has one.
std::string WithHint(const std::string& message) {
  const std::string hint = MujocoHint(message);
  return hint.empty() ? message : message + "\n  hint: " + hint;
}

// Without a network nothing writes the network control source: articulations on it take the ui
// source instead (the panel's sliders), so the panel never shows a source nobody drives.
void NetworkSourcesToUi(world::SceneConfig& scene) {
  using control::ControlSource;
  bool changed = scene.control_source == ControlSource::kNetwork;
  if (changed) scene.control_source = ControlSource::kUi;
  for (world::ArticulationConfig& a : scene.articulations) {
    if (a.control_source == ControlSource::kNetwork) {
      a.control_source = ControlSource::kUi;
      changed = true;
    }
  }
  if (changed) spdlog::info("no network: the network control source is replaced by ui");
}

// --duration D: exactly round(D / timestep) physics steps (the timestep the run starts with),
// whatever the wall clock does. Registered before the physics thread starts, it counts every
// step from the first and pauses the engine after the last one, from the physics thread itself,
// so no further step runs; then it asks the host to stop.
// Threading: the counter is written by the physics thread, read by the main thread.
class DurationLimit : public world::Subsystem {
 public:
  explicit DurationLimit(double seconds) : seconds_(seconds) {}
  std::string_view name() const override { return "duration"; }
  void BeginPlay(world::Session& session) override {
    physics::PhysicsEngine& engine = session.engine();
    steps_ = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(seconds_ / engine.timestep())));
    callback_ = engine.AddOnPostStep([this, &engine](const mjModel*, mjData*) {
      if (done_.load(std::memory_order_relaxed)) return;
      if (++counted_ >= steps_) {
        engine.SetPaused(true);  // before the next iteration: this was the last step
        done_.store(true, std::memory_order_release);
      }
    });
  }
  void EndPlay(world::Session& session) override {
    if (callback_) session.engine().RemoveCallback(*callback_);
    callback_.reset();
  }
  bool RequestsStop() const override { return done_.load(std::memory_order_acquire); }

 private:
  double seconds_;
  std::uint64_t steps_ = 0;
  std::uint64_t counted_ = 0;  // physics thread only
  std::atomic<bool> done_{false};
  std::optional<physics::PhysicsEngine::CallbackId> callback_;
};

// `reopen`: the file the viewer asked to play next (its reload, a dropped scene), "" when none.
int Run(const RunArgs& args, std::string* reopen = nullptr) {
  CurrentInput() = args.scene;
  world::ManagerOptions options;
  options.speed_percent = args.speed;
  options.as_fast_as_possible = args.max_speed;
  options.start_paused = args.paused;
  options.reset_on_divergence = args.reset_on_divergence;
  world::Manager manager(options);
  if (args.duration > 0) manager.AddSubsystem(std::make_unique<DurationLimit>(args.duration));
  // Loading and compiling: a signal ends the process at once (nothing runs, nothing is written).
  world::SceneConfig scene = world::LoadSceneOrModel(args.scene);
  net::NetworkConfig& network_settings = net::EditNetwork(scene);  // the command line changes it
  if (!args.files_dir.empty()) {
    network_settings.files_dir =
        std::filesystem::absolute(args.files_dir).lexically_normal().string();
  }
  if (args.seed) scene.seed = *args.seed;
  ChooseNetworkPorts(network_settings, args.ports, args.port_base);
  if (!args.step_mode.empty()) network_settings.step_mode = args.step_mode;
  // Several environments step only together, in lockstep: the run waits for batch steps.
  if (args.envs > 1) network_settings.step_mode = "direct";
  if (args.envs > 1 && (args.no_network || !network_settings.enabled)) {
    throw Error("--envs " + std::to_string(args.envs) +
                ": several environments are driven through the step server, and the network is "
                "off here");
  }
  if (args.no_network || !network_settings.enabled) NetworkSourcesToUi(scene);
  // Removes at the end only the file this run wrote (also when the run fails).
  std::optional<AnnounceFile> announce;
  if (!args.announce.empty()) {
    CheckOutputs({{args.announce, "--announce"}}, world::SceneInputFiles(scene));
    announce.emplace(args.announce);
  }
  if (!args.video.empty()) {
    CheckOutputs({{args.video[1], "--video"}}, world::SceneInputFiles(scene));
    camera::RequestVideoCamera(scene, args.video[0]);
  }
  replay::RecorderSubsystem* recorder = nullptr;
  if (!args.record.empty()) {
    CheckOutputs({{args.record, "--output"}}, world::SceneInputFiles(scene));
    replay::RecorderOptions rec;
    rec.path = args.record;
    rec.compress = !args.no_compress;
    rec.sensordata = args.sensordata;
    rec.ring_seconds = args.ring_seconds;
    rec.keyframe_interval = args.keyframe_interval;
    auto sub = std::make_unique<replay::RecorderSubsystem>(rec);
    recorder = sub.get();
    manager.AddSubsystem(std::move(sub));
  }
  // A replay a step server client starts (replay_start) shows on the viewer's timeline.
  const auto playback = std::make_shared<replay::PlaybackSlot>();
  world::CameraStreams* cameras = nullptr;
  if (!args.no_cameras || !args.video.empty()) {
    // Added before the network, whose discovery and step server read its streams.
    auto cam_options = camera::CameraOptionsFromScene(scene);
    // The cameras' ports are the network section's: the first one, and the endpoints' to skip.
    cam_options.base_port = network_settings.camera_base_port;
    cam_options.reserved_ports = net::EndpointPorts(network_settings);
    cam_options.publish = !args.no_network && network_settings.enabled;
    if (args.ports == "auto") cam_options.base_port = 0;  // ephemeral ports
    auto sub = std::make_unique<camera::CameraSubsystem>(std::move(cam_options));
    cameras = sub.get();
    manager.AddSubsystem(std::move(sub));
  }
  // --video: frame-exact from the first state (its gate is set before the physics thread runs).
  camera::CameraVideoSubsystem* video_sub = nullptr;
  if (!args.video.empty()) {
    video_sub = &static_cast<camera::CameraVideoSubsystem&>(manager.AddSubsystem(
        std::make_unique<camera::CameraVideoSubsystem>(*cameras, args.video[0], args.video[1])));
  }
  net::NetworkSubsystem* network_sub = nullptr;
  net::NetworkOptions network_options;
  if (!args.no_network && network_settings.enabled) {
    // An idle recorder costs the physics thread nothing; the step server's recording operations
    // use it (added first: it begins before the network and ends after it).
    if (!recorder) {  // --record made one already
      recorder = &static_cast<replay::RecorderSubsystem&>(
          manager.AddSubsystem(std::make_unique<replay::RecorderSubsystem>()));
    }
    net::NetworkOptions net_options = net::NetworkOptionsFromScene(network_settings);
    // A headless run whose port is taken stops before simulating: a client would otherwise
    // drive whichever simulator holds the port. A window's user sees the log line instead.
    net_options.require_bind = !args.view && !args.allow_no_network;
    net_options.scene_name = SceneName(args.scene);
    net_options.instance = args.instance;
    if (net_options.instance.empty()) {
      char host[256] = {};
      ::gethostname(host, sizeof host - 1);
      net_options.instance = fmt::format("{}:{}", host, ::getpid());
    }
    net_options.server_session = NewServerSession();
    // With --envs the I/O thread steps the batch itself (short windows, StepHere): it keeps the
    // physics thread's priority instead of yielding to it.
    if (args.envs > 0) net_options.io_nice = 0;
    // The batched environments (environment 0 is the engine's own; --envs N adds N - 1), driven
    // by the step server's batch operations; added before the network, which uses it.
    world::BatchSubsystemOptions batch_options;
    batch_options.envs = std::max(1, args.envs);
    batch_options.threads = args.threads;
    batch_options.auto_reset = !args.no_auto_reset;
    batch_options.max_episode_steps = args.max_episode_steps;
    batch_options.reset_noise = args.reset_noise;
    batch_options.raw_actions = args.raw_actions;
    batch_options.seed = scene.seed;  // environment i: the run's seed + i
    batch_options.engine_env = args.record_env;
    auto* batch = &static_cast<world::BatchSubsystem&>(
        manager.AddSubsystem(std::make_unique<world::BatchSubsystem>(batch_options)));
    auto network = std::make_unique<net::NetworkSubsystem>(net_options);
    network->SetBatch(batch);
    network_sub = network.get();
    network_options = net_options;
    network->SetRecorder(recorder);
    network->SetCameras(cameras);
    if (args.view) network->SetPlayback(playback);  // the step server's replays on the timeline
    manager.AddSubsystem(std::move(network));
  }
  viewer::ViewerSubsystem* viewer_sub = nullptr;
  if (args.view) {
    viewer::ViewerOptions view_options = args.viewer;
    if (args.envs > 1) {
      view_options.reload_restarts_because =
          "the run steps " + std::to_string(args.envs) +
          " environments (--envs), whose batch keeps the model it began with";
    }
    auto view = std::make_unique<viewer::ViewerSubsystem>(view_options);
    view->SetManager(&manager);
    view->SetRecorder(recorder);  // the panel's Record (none without --record or the network)
    view->SetPlayback(playback);
    viewer_sub = view.get();
    manager.AddSubsystem(std::move(view));
  }
  manager.BeginPlay(scene);
  if (!args.announce.empty()) {  // the rendezvous: written once every socket is bound
    if (!network_sub) {
      network_options.scene_name = SceneName(args.scene);
      network_options.instance = args.instance;
    }
    announce->Write(AnnounceJson(
        network_options,
        network_sub ? network_sub->endpoints() : net::NetworkSubsystem::Endpoints{}, cameras));
    spdlog::info("announced the endpoints in {}", args.announce);
  }
  camera::CameraVideo* video = video_sub ? video_sub->video() : nullptr;
  SetImmediateExit(false);  // playing: a signal stops the loop, which ends cleanly
  // MuJoCo errors and divergences reach us as engine events (delivered inside Tick, on this
  // thread). With auto-reset the engine has reset after a divergence already; errors still come.
  std::optional<physics::EngineEvent> error;
  std::uint64_t errors = 0;
  manager.AddEventListener([&](const physics::EngineEvent& e) {
    // With --envs a divergence ends an episode (the batch's done flag), not the run.
    const bool fatal_divergence = e.kind == physics::EngineEventKind::kDivergence &&
                                  !args.reset_on_divergence && args.envs == 0;
    if (e.kind != physics::EngineEventKind::kError && !fatal_divergence) return;
    ++errors;
    if (!error) error = e;
  });
  physics::PhysicsEngine& engine = manager.session().engine();
  double sim_time = 0;  // summed per log period: a client may change the timestep
  if (args.paused) {
    spdlog::info("paused: send SIGUSR1 to resume (kill -USR1 {}); it toggles pause", ::getpid());
  }

  const auto start = Clock::now();
  auto next_frame = start;
  auto next_log = start + kLogPeriod;
  auto last_log = start;
  auto last_error_log = start - kLogPeriod;
  std::uint64_t errors_logged = 0;
  // Counted from the engine's start (BeginPlay started it): a recording holds every step since.
  std::uint64_t last_steps = 0;
  const std::uint64_t first_steps = 0;
  std::optional<physics::EngineEvent> fatal;
  world::RealTimeWatch realtime;  // warns when a paced run stays behind real time
  while (StopSignal() == 0) {
    manager.Tick();
    if (video) video->Poll();
    if (TakePauseToggle()) {
      const bool pause = !engine.paused();
      ops::SetPaused(manager.session(), pause, ops::When::kNow);
      spdlog::info("{} by SIGUSR1", pause ? "paused" : "resumed");
    }
    const auto now = Clock::now();
    if (auto behind =
            realtime.Update(now, engine.real_time_factor(), engine.speed_percent() / 100.0,
                            !engine.paused() && !engine.as_fast_as_possible())) {
      spdlog::warn("{}", *behind);
    }
    if (error) {
      if (!args.reset_on_divergence) {
        fatal = std::move(error);
        break;
      }
      // Auto-reset is on: back to the initial state and on; logged at most once a second.
      if (now - last_error_log >= kLogPeriod) {
        spdlog::error("{}; reset to the initial state{}", WithHint(error->message),
                      errors - errors_logged > 1 ? fmt::format(" ({} errors since the last report)",
                                                               errors - errors_logged)
                                                 : "");
        errors_logged = errors;
        last_error_log = now;
      }
      error.reset();
      ops::Reset(manager.session(), {});
      ops::SetPaused(manager.session(), false, ops::When::kNow);
    }
    if (now >= next_log) {
      const std::uint64_t steps = engine.step_count();
      const double wall = std::chrono::duration<double>(now - last_log).count();
      const double rate = static_cast<double>(steps - last_steps) / wall;
      const double timestep = engine.timestep();
      sim_time += static_cast<double>(steps - last_steps) * timestep;
      spdlog::info("sim {:.3f} s  rtf={:.3f}  steps/s={:.0f}{}", sim_time, rate * timestep, rate,
                   engine.paused() ? "  (paused)" : "");
      last_steps = steps;
      last_log = now;
      next_log += kLogPeriod;
      if (next_log <= now) next_log = now + kLogPeriod;
    }
    // The window closed, the screenshot was taken, --duration's steps are done.
    if (manager.StopRequested()) break;
    // The recording this command exists for failed (disk full...): stop, and say so.
    if (!args.record.empty() && recorder && recorder->recorder() &&
        recorder->recorder()->status().stopped_because.starts_with("error")) {
      break;
    }
    next_frame += kFrame;
    if (next_frame < now) next_frame = now;  // far behind: do not burst
    std::this_thread::sleep_until(next_frame);
  }
  const int signal = StopSignal();
  // The physics thread stops first, so that the summary, the recording and the video all end at
  // the same step (the video's gate opened first: the thread may be waiting for a frame).
  if (video) video->OpenGate();
  manager.session().Stop();
  const std::uint64_t steps = engine.step_count() - first_steps;
  sim_time += static_cast<double>(engine.step_count() - last_steps) * engine.timestep();
  std::optional<replay::RecorderStatus> recorded;
  if (!args.record.empty() && recorder && recorder->recorder()) {  // not the step server's
    if (recorder->recorder()->active()) {
      recorded = recorder->recorder()->Stop();
    } else {
      recorded = recorder->recorder()->status();
    }
  }
  if (video) video->Poll();
  manager.EndPlay();
  if (reopen && viewer_sub) *reopen = viewer_sub->reload_request();
  FlushMujocoWarningCounts();
  if (announce) announce->Remove();  // nothing is served any more: no launcher may find it
  // The run's products: each failure is reported with what was kept, and makes the exit code 1.
  std::vector<std::string> failures;
  if (video) {
    const int status = video->Close();
    std::printf("video: %s frames=%d%s\n", args.video[1].c_str(), video->frames(),
                status == 0 ? "" : " (ffmpeg failed)");
    if (status != 0) {
      failures.push_back(fmt::format("video {}: ffmpeg failed (exit {}) after {} frames; {}",
                                     args.video[1], status, video->frames(),
                                     WhatIsThere(args.video[1])));
    }
  }
  if (viewer_sub && !viewer_sub->video_error().empty()) {
    failures.push_back(fmt::format("video {}: {}; {}", args.viewer.video, viewer_sub->video_error(),
                                   WhatIsThere(args.viewer.video)));
  }
  if (recorded) {
    std::printf(
        "recording: %s steps=%llu sim=%.3f s bytes=%llu (%.1f bytes/step in data chunks, "
        "%.1f before compression; the embedded model not counted) dropped=%llu%s\n",
        recorded->path.c_str(), static_cast<unsigned long long>(recorded->frames),
        recorded->duration, static_cast<unsigned long long>(recorded->bytes),
        recorded->frames ? static_cast<double>(recorded->data_bytes) / recorded->frames : 0.0,
        recorded->frames ? static_cast<double>(recorded->raw_bytes) / recorded->frames : 0.0,
        static_cast<unsigned long long>(recorded->dropped),
        recorded->stopped_because.starts_with("error") ? " (FAILED)" : "");
    if (recorded->stopped_because.starts_with("error: ")) {
      failures.push_back("recording " + recorded->path +
                         " failed: " + recorded->stopped_because.substr(7));
    }
  }
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  const double sim = sim_time;
  const bool diverged = fatal && fatal->kind == physics::EngineEventKind::kDivergence;
  const std::string how = signal ? std::string(" (stopped by signal ") + SignalName(signal) + ")"
                          : diverged ? " (stopped: the simulation diverged)"
                          : fatal    ? " (stopped by a MuJoCo error)"
                                     : "";
  std::printf("summary: sim_time=%.3f s steps=%llu wall=%.3f s mean_rtf=%.3f%s\n", sim,
              static_cast<unsigned long long>(steps), wall, wall > 0 ? sim / wall : 0.0,
              how.c_str());
  std::fflush(stdout);
  if (fatal) {
    std::string message = fatal->message;
    constexpr std::string_view kEnginePrefix = "physics loop paused after an error: ";
    if (message.starts_with(kEnginePrefix)) message.erase(0, kEnginePrefix.size());
    std::cerr << "urlab: error: " << args.scene << ": at t=" << fatal->sim_time
              << " s: " << WithHint(message)
              << (diverged ? "\n  hint: a smaller timestep, more damping or armature, or gains "
                             "the actuators can follow usually keep it stable"
                           : "")
              << "\n  (--reset-on-divergence resets and goes on instead)\n";
  }
  for (const std::string& f : failures) std::cerr << "urlab: error: " << f << "\n";
  if (fatal) return 1;
  if (signal) return ExitCodeForSignal(signal);
  return failures.empty() ? 0 : 1;
}

// An integer written as one (CLI11 would otherwise report a fraction as a conversion error).
const CLI::Validator kInteger(
    [](std::string& text) -> std::string {
      std::size_t used = 0;
      try {
        (void)std::stoll(text, &used);
      } catch (const std::exception&) {
        return "'" + text + "' is not an integer";
      }
      if (used != text.size()) return "'" + text + "' is not an integer";
      return {};
    },
    "");

// A folder, or a path where one can be made (not an existing file).
const CLI::Validator kFolderOrAbsent(
    [](std::string& text) -> std::string {
      std::error_code ec;
      if (text.empty()) return "must name a folder";
      if (std::filesystem::exists(text, ec) && !std::filesystem::is_directory(text, ec)) {
        return text + " exists and is not a folder";
      }
      return {};
    },
    "FOLDER");

}  // namespace

namespace {

// The options `run` and `record` share.
void AddRunOptions(CLI::App* cmd, RunArgs& args) {
  cmd->add_option("SCENE", args.scene, "scene file (.yaml) or MJCF model (.xml)")->required();
  cmd->add_option("--duration", args.duration,
                  "stop after this many simulated seconds: exactly round(SECONDS / timestep) "
                  "physics steps, at any pace (real time: as many wall-clock seconds); default: "
                  "run until Ctrl-C")
      ->check(kFinitePositive);
  CLI::Option* speed =
      cmd->add_option("--speed", args.speed, "simulation speed in percent of real time (5-100)")
          ->check(kInteger)
          ->check(CLI::Range(5, 100));
  CLI::Option* max_speed =
      cmd->add_flag("--max-speed", args.max_speed, "step as fast as possible (no pacing)");
  speed->excludes(max_speed);
  cmd->add_flag("--paused", args.paused,
                "start paused (SIGUSR1 resumes; so does a step server client's set_paused)");
  cmd->add_flag("--no-cameras", args.no_cameras,
                "render no camera (by default the cameras the scene streams render off-screen and "
                "publish from network.camera_base_port, 5558, upward)");
  cmd->add_flag(
      "--no-network", args.no_network,
      "no ZeroMQ sockets (by default the streaming topics and the step server of "
      "docs/protocol.md are served on the scene's endpoints or the defaults 5555-5557, 5559)");
  CLI::Option* ports =
      cmd->add_option("--ports", args.ports,
                      "auto: the system chooses a free port for every TCP socket (state, "
                      "control, info, cameras, step server; see --announce), so any number of "
                      "runs share a machine; scene (default): the scene's network: section")
          ->check(CLI::IsMember({"auto", "scene"}));
  cmd->add_option("--port-base", args.port_base,
                  "N: state on port N, control N+1, info N+2, cameras from N+3 upward, step "
                  "server N+4 (the defaults are N = 5555); the scene's hosts are kept")
      ->check(kInteger)
      ->check(CLI::Range(1, 65531))
      ->excludes(ports);
  cmd->add_option("--announce", args.announce,
                  "write the bound endpoints, the step server's transports, the scene name, the "
                  "instance id and this run's session id to FILE as JSON once every socket is "
                  "bound (written whole: a launcher waits for the file); removed when the run "
                  "ends (docs/network.md, \"Ports, the announce file and the server's identity\")")
      ->check(OutputPath());
  cmd->add_option("--instance", args.instance,
                  "this run's instance id, in the step server's hello_ok and the announce file "
                  "(clients may require it; default HOST:PID)");
  cmd->add_option("--step-mode", args.step_mode,
                  "the step server's initial mode, which it returns to when its driver leaves: "
                  "live (the physics runs by itself) or direct (lockstep: it steps only when a "
                  "client asks); replaces the scene's network.step_mode")
      ->check(CLI::IsMember({"live", "direct"}));
  CLI::Option* envs =
      cmd->add_option("--envs", args.envs,
                      "N independent copies of the scene (one model, N simulations) stepped "
                      "together in lockstep by the step server's batch operations (batch_info, "
                      "batch_step, batch_reset; docs/network.md \"Batched environments\"); the "
                      "topics, the viewer and a recording follow environment 0 (--record-env); "
                      "implies "
                      "--step-mode direct when N > 1, and a divergence ends that environment's "
                      "episode instead of the run (default 1)")
          ->check(kInteger)
          ->check(CLI::Range(1, 65536));
  cmd->add_option("--threads", args.threads,
                  "threads stepping the environments of --envs (default: the machine's cores, at "
                  "most N)")
      ->check(kInteger)
      ->check(CLI::Range(1, 1024))
      ->needs(envs);
  cmd->add_option("--record-env", args.record_env,
                  "with --envs: the environment the engine itself runs, which the recording "
                  "(--record, recording_start), the streaming topics and the viewer follow "
                  "(default 0; at most N-1)")
      ->check(kInteger)
      ->check(CLI::Range(0, 65535))
      ->needs(envs);
  cmd->add_flag("--no-auto-reset", args.no_auto_reset,
                "with --envs: an ended episode waits for batch_reset (by default the next "
                "batch_step resets it, ignoring its action: gymnasium's next-step autoreset)")
      ->needs(envs);
  cmd->add_option("--max-episode-steps", args.max_episode_steps,
                  "with --envs: an episode ends after this many physics steps (default: only a "
                  "divergence ends it)")
      ->check(kInteger)
      ->check(CLI::Range(1, 1000000000))
      ->needs(envs);
  cmd->add_option("--reset-noise", args.reset_noise,
                  "with --envs: uniform noise of this scale added at each reset to hinge, slide "
                  "and free-joint positions and to every velocity, from each environment's own "
                  "generator (default 0)")
      ->check(CLI::Range(0.0, 1e6))
      ->needs(envs);
  cmd->add_flag("--raw-actions", args.raw_actions,
                "with --envs: batch steps' actions are each actuator's control (ctrl) and the "
                "scene's controllers do not run in the environments (default: every environment "
                "runs the scene's controllers, so a PD scene takes joint targets)")
      ->needs(envs);
  cmd->add_flag("--allow-no-network", args.allow_no_network,
                "go on without a socket that cannot bind (by default a run without a window "
                "whose port is taken exits 1 before simulating, naming the process holding it)");
  cmd->add_option("--files-dir", args.files_dir,
                  "the folder whose files step-server clients may write and read by name "
                  "(snapshots, recordings, replays; never a path, never over an existing file "
                  "without overwrite and the lease, never over the scene's inputs); replaces the "
                  "scene's network.files_dir (default: recordings/ in the working folder)")
      ->check(kFolderOrAbsent);
  cmd->add_option("--seed", args.seed,
                  "the run's seed, from which every emulated delay's jitter and every "
                  "randomisation is drawn (the scene's `latency:` and `randomize:` sections); with "
                  "--envs environment i's generator starts with seed + i; replaces the scene's "
                  "seed (default 0)");
  cmd->add_flag("--reset-on-divergence", args.reset_on_divergence,
                "reset to the initial state when the simulation diverges (NaN/Inf, MuJoCo's "
                "instability warnings) or MuJoCo reports an error, and go on (by default either "
                "stops the run with its message and exit 1)");
}

}  // namespace

void AddRenderQualityOptions(CLI::App* cmd, viewer::ViewerOptions& v) {
  // These win over the scene's `viewer:` section; by default all are on (with a 1024 shadow map
  // under a software renderer).
  const auto on_off = [cmd](const char* name, std::optional<bool>& value, const char* what,
                            const char* scene_key) {
    cmd->add_flag_callback(
        std::string("--") + name, [&value] { value = true; },
        fmt::format("draw {} (the default; scene: viewer.{})", what, scene_key));
    cmd->add_flag_callback(
        std::string("--no-") + name, [&value] { value = false; },
        fmt::format("no {} (faster under software rendering)", what));
  };
  on_off("shadows", v.shadows, "shadows", "shadows");
  on_off("reflections", v.reflections, "reflections on reflective floors", "reflections");
  on_off("skybox", v.skybox, "the sky (the model's skybox texture, else a gradient)", "skybox");
  cmd->add_option("--render-scale", v.render_scale,
                  "3D view resolution per window pixel, 0.25 to 2 (below 1: faster under software "
                  "rendering; above 1: smoother edges; default 1; scene: viewer.render_scale)")
      ->check(CLI::Range(0.25, 2.0));
}

namespace {

void AddViewOptions(CLI::App* cmd, RunArgs& args) {
  viewer::ViewerOptions& v = args.viewer;
  cmd->add_option("--width", v.width, "window width in pixels (default 1280)")
      ->check(CLI::Range(64, 8192));
  cmd->add_option("--height", v.height, "window height in pixels (default 720)")
      ->check(CLI::Range(64, 8192));
  CLI::Option* shot = cmd->add_option(
      "--screenshot", v.screenshot,
      "write a PNG of the window showing the first state at --at seconds of simulation time "
      "(the simulation waits for the shot), then stop (exit 0)");
  shot->check(OutputPath());
  cmd->add_option("--at", v.screenshot_at, "simulation time of --screenshot (default 0)")
      ->check(CLI::NonNegativeNumber)
      ->needs(shot);
  cmd->add_flag("--debug-all", v.debug_all,
                "start with contact forces, collision wireframes, joint axes and sites drawn");
  cmd->add_option("--video", v.video,
                  "record the window to a video file (.mp4 or .webm; ffmpeg), frame-exact: frame k "
                  "shows the simulation k/fps simulated seconds after the start (the simulation "
                  "waits for frames the renderer is late with, so a slow renderer makes the run "
                  "slower, not the video shorter); if ffmpeg fails the command exits 1")
      ->check(OutputPath());
  cmd->add_option("--video-fps", v.video_fps, "frames per second of --video (default 30)")
      ->check(CLI::Range(1, 240));
  cmd->add_flag_callback(
      "--no-panel", [&v] { v.panel = false; }, "no simulate panel");
  AddRenderQualityOptions(cmd, v);
  cmd->add_option("--plot", v.plots,
                  "plot this signal over time from the start (repeatable, at most 8): a joint "
                  "(left_shoulder), a sensor value (left_tip_pos[2]) or an actuator force "
                  "(\"left_shoulder_motor force\"), as the panel's Plots section lists them; F4 "
                  "shows or hides the plots");
}

// Runs, and again on the file the viewer asks for (Reload, a scene, model or recording dropped
// on the window); a file that fails to load is reported and the previous one plays again.
int RunViewing(const RunArgs& args) {
  RunArgs a = args;
  std::string previous;
  for (;;) {
    std::string reopen;
    int code = 0;
    try {
      code = IsRecordingPath(a.scene) ? ViewRecording(a.scene, a.viewer, &reopen) : Run(a, &reopen);
    } catch (const std::exception& e) {
      if (previous.empty()) throw;
      spdlog::error("cannot open {}: {}; back to {}", a.scene, e.what(), previous);
      a.scene = previous;
      previous.clear();
      continue;
    }
    if (reopen.empty() || StopSignal() != 0) return code;
    previous = a.scene;
    a.scene = reopen;
    spdlog::info("viewer: opening {}", reopen);
    SetImmediateExit(true);  // loading again: a signal ends the process at once
  }
}

void AddRecordOptions(CLI::App* cmd, RunArgs& args) {
  cmd->add_flag("--no-compress", args.no_compress, "store chunks without zstd compression");
  cmd->add_flag("--sensordata", args.sensordata, "also record every sensor value of every step");
  cmd->add_option("--ring", args.ring_seconds,
                  "keep only the last SECONDS of simulated time (in memory; written at the end)")
      ->check(kFinitePositive);
  cmd->add_option("--keyframe-interval", args.keyframe_interval,
                  "simulated seconds between full-state keyframes (seek points; default 1)")
      ->check(kFinitePositive);
}

}  // namespace

int ViewFiles(const std::string& file, const viewer::ViewerOptions& viewer) {
  RunArgs args;
  args.scene = file;
  args.view = true;
  args.viewer = viewer;
  return RunViewing(args);
}

void RegisterRecordCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Play a scene like `urlab run` and record every physics step to a .urrec file: time, qpos, "
      "qvel, act, ctrl, mocap poses, applied forces (one-shot included), optionally sensordata; "
      "the state at every reset, restore or state write; keyframes for seeking. The file is "
      "written as FILE.part (flushed at least once a second, so a crash loses at most about a "
      "second) and renamed to FILE when the recording ends (--duration, Ctrl-C, SIGTERM). An "
      "existing FILE.part (a crashed recording) is never overwritten: the command refuses, and "
      "`urlab replay FILE.part --info` (or --export-csv, or playback) recovers it. A device or "
      "FIFO (/dev/null, a named pipe) is written in place; a symlink gets the recording through "
      "the link. If the recording or a --video fails (disk full, ffmpeg), the command exits 1 "
      "and says what was kept. `urlab replay` plays, checks and exports it.");
  static RunArgs args;
  AddRunOptions(cmd, args);
  cmd->add_option("-o,--output", args.record, "the recording to write (.urrec)")
      ->check(OutputPath());
  cmd->add_option("--video", args.video,
                  "CAM OUT: also (or only) write camera CAM (articulation/camera, an MJCF camera) "
                  "to OUT (.mp4 H.264 or .webm VP9) through ffmpeg, at the camera's rate and size "
                  "(the scene's cameras: section), frame-exact: frame k shows the state k/rate "
                  "simulated seconds after the start (the simulation waits for a camera that is "
                  "late, with --max-speed too); if ffmpeg fails the command exits 1")
      ->expected(2)
      ->check(OutputPath());
  AddRecordOptions(cmd, args);
  cmd->callback([&exit_code] {
    if (args.record.empty() && args.video.empty()) {
      throw CLI::RequiredError("--output (or --video)");
    }
    exit_code = Run(args);
  });
}

void RegisterViewCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Play a scene like `urlab run`, in a window: MuJoCo's renderer beside the simulate panel "
      "(docked at the left; drag its edge to resize, H hides it; a menu bar with File, "
      "Simulation, View, Render and Physics), the default camera framing the whole scene "
      "(Ctrl+A), debug drawing (keys 1-5), pause (P), single step (Right, while paused), reset "
      "(R), the model's cameras ([ ]), help (F1), info (F2), profiler (F3), plots (F4, --plot), "
      "save XML / MJB (Ctrl+S, Ctrl+Shift+S), print model / data (Ctrl+M, Ctrl+D), load / save "
      "key and copy pose (Ctrl+K, Ctrl+Shift+K, Ctrl+C), reload (Ctrl+L: changed values in the "
      "models are taken where the simulation is, keeping its state; a changed structure or scene "
      "file, --envs or a recording under way starts it again; or drop a scene, an MJCF file or a "
      "recording on the window), "
      "cinematic cameras (O), launchers (F), possession "
      "(Tab, then "
      "WASD/QE or a gamepad), mouse camera (left drag rotate, right drag move, wheel zoom, "
      "double-click select, Ctrl+right double-click track) and Ctrl+drag perturbation. Closing "
      "the window stops it (exit 0). Needs a display (xvfb-run works).");
  static RunArgs args;
  args.view = true;
  AddRunOptions(cmd, args);
  cmd->get_option("SCENE")->description(
      "scene file (.yaml), MJCF model (.xml), or a recording (.urrec) to watch with the replay "
      "timeline as `urlab replay FILE --view` does");
  AddViewOptions(cmd, args);
  cmd->callback([&exit_code] { exit_code = RunViewing(args); });
}

void RegisterRunCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Play a scene (YAML) or a single MJCF model headless: physics on its own thread, "
      "controllers, initial keyframes. Logs the real-time factor once a second and warns when "
      "it stays below 95 % of the speed asked for (3 s, then every 30 s). Ctrl-C, SIGTERM "
      "or SIGHUP stops it cleanly, prints a summary and exits 128+signal (130, 143, 129); "
      "--duration ends it with exit 0; during loading a signal exits at once (a second one "
      "forces a stuck stop). SIGUSR1 toggles pause. A MuJoCo error or a divergence stops it "
      "with the message and exit 1 unless --reset-on-divergence.");
  static RunArgs args;
  AddRunOptions(cmd, args);
  cmd->add_option("--record", args.record,
                  "also record every step to this .urrec file (see `urlab record --help`)")
      ->check(OutputPath());
  AddRecordOptions(cmd, args);
  cmd->add_flag("--view", args.view, "open the viewer window (see `urlab view --help`)");
  AddViewOptions(cmd, args);
  cmd->callback([&exit_code] { exit_code = args.view ? RunViewing(args) : Run(args); });
}

}  // namespace urlab::app
