// `urlab run`: the headless main job. Plays a scene with the Manager, ticking it at ~60 Hz on the
// main thread, logs the real-time factor and step rate once a second and stops cleanly on
// Ctrl-C / SIGTERM or after --duration.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include "app/commands.h"
#include "urlab/net/network.h"
#include "urlab/world/manager.h"

namespace urlab::app {

namespace {

using Clock = std::chrono::steady_clock;

// Set by the signal handler, polled by the main loop.
std::atomic<bool> g_stop_requested{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void OnStopSignal(int /*signal*/) { g_stop_requested.store(true); }

constexpr auto kFrame = std::chrono::microseconds(16667);  // ~60 Hz main-thread tick
constexpr auto kLogPeriod = std::chrono::seconds(1);

struct RunArgs {
  std::string scene;
  double duration = 0;  // wall seconds, 0: until a signal
  int speed = 100;
  bool max_speed = false;
  bool paused = false;
  bool reset_on_divergence = false;
  bool no_network = false;
};

int Run(const RunArgs& args) {
  g_stop_requested.store(false);
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);

  world::ManagerOptions options;
  options.speed_percent = args.speed;
  options.as_fast_as_possible = args.max_speed;
  options.start_paused = args.paused;
  options.reset_on_divergence = args.reset_on_divergence;
  world::Manager manager(options);
  const world::SceneConfig scene = world::LoadSceneOrModel(args.scene);
  if (!args.no_network && scene.network.enabled) {
    manager.AddSubsystem(
        std::make_unique<net::NetworkSubsystem>(net::NetworkOptionsFromScene(scene.network)));
  }
  manager.BeginPlay(scene);
  physics::PhysicsEngine& engine = manager.session().engine();
  const double timestep = engine.model()->opt.timestep;

  const auto start = Clock::now();
  auto next_frame = start;
  auto next_log = start + kLogPeriod;
  auto last_log = start;
  std::uint64_t last_steps = engine.step_count();
  const std::uint64_t first_steps = last_steps;
  while (!g_stop_requested.load()) {
    manager.Tick();
    const auto now = Clock::now();
    if (now >= next_log) {
      const std::uint64_t steps = engine.step_count();
      const double wall = std::chrono::duration<double>(now - last_log).count();
      const double rate = static_cast<double>(steps - last_steps) / wall;
      spdlog::info("sim {:.3f} s  rtf={:.3f}  steps/s={:.0f}{}",
                   static_cast<double>(steps - first_steps) * timestep, rate * timestep, rate,
                   engine.paused() ? "  (paused)" : "");
      last_steps = steps;
      last_log = now;
      next_log += kLogPeriod;
      if (next_log <= now) next_log = now + kLogPeriod;
    }
    if (args.duration > 0 && now - start >= std::chrono::duration<double>(args.duration)) break;
    next_frame += kFrame;
    if (next_frame < now) next_frame = now;  // far behind: do not burst
    std::this_thread::sleep_until(next_frame);
  }
  const bool interrupted = g_stop_requested.load();
  const std::uint64_t steps = engine.step_count() - first_steps;
  manager.EndPlay();
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  const double sim = static_cast<double>(steps) * timestep;
  std::printf("summary: sim_time=%.3f s steps=%llu wall=%.3f s mean_rtf=%.3f%s\n", sim,
              static_cast<unsigned long long>(steps), wall, wall > 0 ? sim / wall : 0.0,
              interrupted ? " (stopped by signal)" : "");
  std::fflush(stdout);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  return 0;
}

}  // namespace

void RegisterRunCommand(CLI::App& app, int& exit_code) {
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Play a scene (YAML) or a single MJCF model headless: physics on its own thread, "
      "controllers, initial keyframes. Logs the real-time factor once a second; Ctrl-C or "
      "SIGTERM stops it cleanly and prints a summary.");
  static RunArgs args;
  cmd->add_option("SCENE", args.scene, "scene file (.yaml) or MJCF model (.xml)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--duration", args.duration,
                  "stop after this many wall-clock seconds (default: run until Ctrl-C)")
      ->check(CLI::PositiveNumber);
  CLI::Option* speed =
      cmd->add_option("--speed", args.speed, "simulation speed in percent of real time (5-100)")
          ->check(CLI::Range(5, 100));
  CLI::Option* max_speed =
      cmd->add_flag("--max-speed", args.max_speed, "step as fast as possible (no pacing)");
  speed->excludes(max_speed);
  cmd->add_flag("--paused", args.paused, "start paused");
  cmd->add_flag("--no-network", args.no_network,
                "no ZeroMQ sockets (by default the state, control and info topics of "
                "protocol.md are served on the scene's endpoints or the defaults 5555-5557)");
  cmd->add_flag("--reset-on-divergence", args.reset_on_divergence,
                "reset to the initial state when the simulation diverges");
  cmd->callback([&exit_code] { exit_code = Run(args); });
}

}  // namespace urlab::app
