// `urlab bench`: benchmarks that print a ratio against a baseline measured in the same process.
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/python_env.h"
#include "urlab/camera/camera_bench.h"
#include "urlab/net/broadcast_bench.h"
#include "urlab/net/fleet_bench.h"
#include "urlab/net/latency_bench.h"
#include "urlab/replay/recorder.h"
#include "urlab/viewer/view_bench.h"
#include "urlab/world/loop_bench.h"
#include "urlab/world/manager.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"

namespace urlab::app {

namespace {

struct BenchLoopArgs {
  std::string scene;
  int steps = 10000;
  int trials = 15;
  int subscribers = 0;
  bool network = false;
  bool record = false;
  bool view = false;
  CLI::Option* trials_option = nullptr;
};

// bench loop --network: the loop with the network subsystem broadcasting against without.
int BenchLoopNetwork(const BenchLoopArgs& args) {
  world::SceneConfig scene = world::LoadSceneOrModel(args.scene);
  scene.articulations.resize(1);  // the first articulation only
  world::ArticulationConfig& art = scene.articulations.front();
  if (art.controller.type == "none") art.controller.type = "pd";
  net::BroadcastBenchOptions options;
  options.trials = args.trials_option->count() > 0 ? args.trials : 5;
  options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  std::printf(
      "scene %s: articulation '%s', controller %s; every streaming topic and state/full "
      "(%s) on every step\n",
      scene.path.c_str(), art.name.c_str(), art.controller.type.c_str(),
      options.full_state.c_str());
  const net::BroadcastBenchResult r = net::RunBroadcastBench(scene, options);
  std::printf("ratio=%.4f\n", r.ratio);
  std::fflush(stdout);
  return 0;
}

int BenchLoop(const BenchLoopArgs& args) {
  CurrentInput() = args.scene;
  if (args.network) return BenchLoopNetwork(args);
  world::SceneConfig scene = world::LoadSceneOrModel(args.scene);
  scene.articulations.resize(1);  // the first articulation only
  scene.save_debug_xml.clear();
  // Exactly what begin-play builds and checks (world/scene_checks.h).
  const world::CompiledScene compiled = world::BuildCheckedScene(scene);

  world::LoopBenchOptions options;
  options.steps = args.steps;
  options.trials = args.trials;
  options.subscribers = args.subscribers;
  const world::ArticulationConfig art = world::DriveFirstArticulation(scene, compiled, &options);
  options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  // --record: each trial also runs the loop with a recorder writing a compressed file.
  std::unique_ptr<replay::Recorder> recorder;
  const std::string folder =
      (std::filesystem::temp_directory_path() / fmt::format("urlab-bench-{}", ::getpid())).string();
  if (args.record) {
    options.attach = [&](physics::PhysicsEngine& engine) {
      recorder = std::make_unique<replay::Recorder>(
          engine, replay::RecorderSource{{art.name}, "", scene.path});
    };
    options.toggle = [&](bool on) {
      if (on) {
        replay::RecorderOptions o;
        o.path = folder + "/bench.urrec";
        recorder->Start(o);
      } else {
        const replay::RecorderStatus st = recorder->Stop();
        std::printf("recorded %llu steps, %llu bytes (%.1f bytes/step), %llu dropped\n",
                    static_cast<unsigned long long>(st.frames),
                    static_cast<unsigned long long>(st.bytes),
                    st.frames ? static_cast<double>(st.bytes) / st.frames : 0.0,
                    static_cast<unsigned long long>(st.dropped));
      }
    };
  }
  std::printf("scene %s: articulation '%s', controller %s\n", scene.path.c_str(), art.name.c_str(),
              art.controller.type.c_str());
  if (args.view) {
    const viewer::ViewBenchResult v =
        viewer::RunLoopBenchWithView(compiled.model, options, viewer::ViewerOptions{});
    std::printf("viewer: %llu frames at 1280x720, %.1f frames/s of drawing time\n",
                static_cast<unsigned long long>(v.frames), v.fps);
    std::printf("view_ratio=%.4f\n", v.loop.attached_ratio);
    std::printf("ratio=%.4f\n", v.loop.ratio);
    std::fflush(stdout);
    return 0;
  }
  const world::LoopBenchResult r = world::RunLoopBench(compiled.model, options);
  if (args.record) {
    recorder.reset();
    std::error_code ec;
    std::filesystem::remove_all(folder, ec);
    std::printf("record_ratio=%.4f\n", r.attached_ratio);
  }
  std::printf("ratio=%.4f\n", r.ratio);
  std::fflush(stdout);
  return 0;
}

struct BenchLatencyArgs {
  std::string scene;
  int samples = 2000;
};

int BenchLatency(const BenchLatencyArgs& args) {
  net::LatencyBenchOptions options;
  options.samples = args.samples;
  options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  const net::LatencyBenchResult r =
      net::RunLatencyBench(world::LoadSceneOrModel(args.scene), options);
  std::printf(
      "streaming_ratio=%.3f\nlockstep_ratio=%.3f\nthroughput_n1=%.3f\nthroughput_n10=%.3f\n"
      "ceiling_n1=%.3f\nceiling_n10=%.3f\npipelined_n1=%.3f\npipelined_n10=%.3f\n",
      r.streaming.p50_us / r.raw_pubsub.p50_us, r.lockstep.p50_us / r.raw_reqrep.p50_us,
      r.throughput_ratio_n1, r.throughput_ratio_n10, r.ceiling_n1, r.ceiling_n10,
      r.pipelined_ratio_n1, r.pipelined_ratio_n10);
  std::fflush(stdout);
  return 0;
}

// liburlab_batch.so beside this program (a build tree) or in its ../lib, ../lib/* (an
// installation); "" when there is none.
std::string BatchLibraryBesideThisProgram() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const fs::path dir = exe.parent_path();
  const char* name = "liburlab_batch.so";
  for (const fs::path& p : {dir / name, dir / ".." / "lib" / name}) {
    if (fs::exists(p, ec)) return p.lexically_normal().string();
  }
  for (const auto& entry : fs::directory_iterator(dir / ".." / "lib", ec)) {
    if (entry.is_directory(ec) && fs::exists(entry.path() / name, ec)) {
      return (entry.path() / name).lexically_normal().string();
    }
  }
  return "";
}

// bench peers: the options, passed to bench/peers.py.
struct BenchPeersArgs {
  std::string model;
  std::vector<int> envs = {1, 16, 64};
  int threads = 2;
  double seconds = 2.0;
  int repeats = 5;
  int frame_skip = 5;
  std::vector<std::string> skip;
  std::string python;
  std::string batch_library;
  std::string python_client;
};

// Replaces this process with the Python benchmark (its output and exit status are the command's).
int RunBenchPeers(const BenchPeersArgs& args) {
  const std::string program = std::string(URLAB_SOURCE_DIR) + "/bench/peers.py";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(program, ec)) {
    std::cerr << "urlab: error: bench peers: no benchmark program at " << program << "\n";
    return 1;
  }
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  std::string envs;
  for (int n : args.envs) envs += (envs.empty() ? "" : ",") + std::to_string(n);
  std::string skip;
  for (const std::string& s : args.skip) skip += (skip.empty() ? "" : ",") + s;
  std::vector<std::string> argv_s = {args.python,       program,
                                     "--envs",          envs,
                                     "--threads",       std::to_string(args.threads),
                                     "--seconds",       fmt::format("{}", args.seconds),
                                     "--repeats",       std::to_string(args.repeats),
                                     "--frame-skip",    std::to_string(args.frame_skip),
                                     "--skip",          skip,
                                     "--urlab",         ec ? std::string() : self.string(),
                                     "--batch-library", args.batch_library,
                                     "--client",        args.python_client};
  if (!args.model.empty()) {
    argv_s.push_back("--model");
    argv_s.push_back(args.model);
  }
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  ::execv(argv[0], argv.data());
  std::cerr << "urlab: error: bench peers: cannot run " << argv_s[0] << ": " << std::strerror(errno)
            << "\n";
  return 1;
}

}  // namespace

void RegisterBenchCommand(CLI::App& app, int& exit_code) {
  CLI::App* bench =
      app.add_subcommand("bench", "Benchmarks against a baseline in the same process.");
  bench->require_subcommand(1);
  CLI::App* loop = bench->add_subcommand(
      "loop",
      "Step rate of the full physics loop (physics thread, the scene's first articulation with "
      "its controller (PD if none), one pre- and one post-step callback, as fast as possible) "
      "divided by a bare mj_step loop on the same model; prints ratio=<value> last.");
  static BenchLoopArgs args;
  loop->add_option("SCENE", args.scene, "scene file (.yaml) or MJCF model (.xml)")->required();
  loop->add_option("--steps", args.steps, "steps per trial")->check(CLI::Range(2, 100000000));
  args.trials_option = loop->add_option("--trials", args.trials,
                                        "trials per loop (best of; with --network: pairs of "
                                        "trials, median, default 5)")
                           ->check(CLI::Range(1, 1000));
  loop->add_option("--subscribers", args.subscribers,
                   "state readers attached to the loop: an every-step ring, then newest-frame "
                   "readers polling at 1 kHz and 60 Hz in turn")
      ->check(CLI::Range(0, 16));
  loop->add_flag("--record", args.record,
                 "also run each trial's loop with the recorder writing every step to a "
                 "compressed recording (in the temporary folder, removed after), and print "
                 "record_ratio=<loop with recorder / loop without> before ratio=");
  loop->add_flag("--view", args.view,
                 "also run each trial's loop with the viewer drawing its newest state frame at "
                 "60 Hz in a 1280x720 window (every debug layer on; needs a display, xvfb-run "
                 "works), and print view_ratio=<loop with viewer / loop without> before ratio=")
      ->excludes("--record");
  loop->add_flag("--network", args.network,
                 "instead: the loop with the network subsystem publishing every streaming topic "
                 "and state/full on every step to a subscriber on loopback, against the loop "
                 "without it (alternating 1 s trials); prints ratio=<with/without> last");
  loop->callback([&exit_code] { exit_code = BenchLoop(args); });

  CLI::App* latency = bench->add_subcommand(
      "latency",
      "Network latency and lockstep throughput over loopback: control-to-state round trip on the "
      "streaming topics and step n=1 round trip on the step server (p50/p99), each beside a raw "
      "ZeroMQ ping-pong of the same kind measured in the same run (the echo in its own ZeroMQ "
      "context, like another process), and steps per second through the step server (n=1, "
      "n=10) against a bare mj_step loop: with one request in flight (a learning loop; printed "
      "beside what adding the raw round trip's median to each step would give: an estimate a "
      "run can beat, not a bound) and with 4 in flight (the server's capacity). "
      "The scene's first articulation runs with passthrough control, as fast as possible. The "
      "last lines are key=value ratios for scripts.");
  static BenchLatencyArgs latency_args;
  latency->add_option("SCENE", latency_args.scene, "scene file (.yaml) or MJCF model (.xml)")
      ->required()
      ->check(CLI::ExistingFile);
  latency->add_option("--samples", latency_args.samples, "round trips per measurement")
      ->check(CLI::Range(10, 1000000));
  latency->callback([&exit_code] { exit_code = BenchLatency(latency_args); });

  CLI::App* fleet = bench->add_subcommand(
      "fleet",
      "Driving simulations from learning code: lockstep steps per second through the step "
      "server (n=1 and n=10 steps per request) over ZeroMQ and over the shared-memory channel, "
      "from C++ and from a Python client in its own process, as ratios of a bare single-thread "
      "mj_step loop measured in the same run (alternating rounds, medians; each round's bare "
      "loop steps from the served simulation's state of that moment), beside raw ZeroMQ "
      "and raw shared-memory ping-pongs and the step server's round trips. The scene's first "
      "articulation runs with passthrough control, as fast as possible. Prints one key=value "
      "line per figure last (bare_steps_per_s, raw_zmq_rtt_p50_us, raw_shm_rtt_p50_us, zmq_n1, "
      "zmq_n10, zmq_step_rtt_p50_us, zmq_rtt_p50_us, shm_n1, shm_n10, shm_step_rtt_p50_us, "
      "shm_rtt_p50_us, zmq_python_n1, shm_python_n1), then a batched server (urlab run --envs N "
      "--threads 2 --raw-actions, its own process) through the Python vector env at N = 1, 16, "
      "64, 256, stepping random actions within the ctrlranges, whose ratios are over a bare "
      "single-thread loop stepping the same trajectories (the same actions from the same reset "
      "state, one environment after another) in the same round: batchN_python_ratio, "
      "batchN_server_ratio, batchN_server_env_steps_per_s; batch64_ratio, python_overhead64 = "
      "1 - Python rate / the server's own batched rate, batch64_bare_steps_per_s (that bare "
      "loop's rate), batch64_action_cost (the zero-control bare rate over it: what the actions "
      "add per step), batch64_ceiling (2 plain threads stepping those trajectories, 32 each in "
      "turn as the batch does, over that bare loop), batch64_of_ceiling (the Python rate over "
      "that ceiling) and batch64_frameskip5_ratio (the same 64 environments with n_steps 5 per "
      "request, each action held for 5 physics steps, over a bare loop stepping those "
      "trajectories). Beside them "
      "parallel_ceiling (2 plain threads, each stepping its own mjData with no "
      "synchronisation, over the bare loop: what 2 cores give at all) and parallel_ceiling64 "
      "(the same with 32 mjData per thread stepped in turn: what 2 cores give to 64 "
      "simulations); batch64_ratio is the "
      "synchronous step() over that one server. Then the same 64 environments as two servers "
      "of 32 with one thread each, through one vector env: batch2x32_sync_ratio (step()) and "
      "batch2x32_async_ratio (send/recv: one server steps while Python handles the other's "
      "reply). Then the same 64 environments inside the Python script's own process, with no "
      "server "
      "(UrlabVectorEnv.in_process over liburlab_batch.so, --batch-library; 2 threads): "
      "batch64_inproc_ratio (over the bare loop stepping the same trajectories), "
      "batch64_inproc_step_ratio (the library's own step), inproc_overhead64 (1 - the Python "
      "rate over that) and batch64_inproc_of_ceiling (over batch64_ceiling's rate). Last, with "
      "python3-distributed, a Dask LocalCluster of 1 and 2 workers with one "
      "batched server of 16 environments each: dask_scaling (2 workers over 1) and "
      "dask_of_ceiling (that over what 2 plain threads make of the bare loop just after); then "
      "the same clusters with rollout workers (urlab_client.rollout: 16 in-process environments "
      "per worker, stepped by the worker with the policy each call sends, the driver out of the "
      "step loop): dask_rollout_scaling (2 workers over 1) and dask_rollout_of_ceiling. "
      "bare_spread comes last: the bare loop's fastest round over its slowest in the whole run "
      "(above 1.15 a line says the machine was busy and the ratios are unreliable).");
  static net::FleetBenchOptions fleet_args;
  static std::string fleet_scene;
#ifdef URLAB_PYTHON_CLIENT_DIR
  fleet_args.python_client = URLAB_PYTHON_CLIENT_DIR;
  fleet_args.python = PythonInterpreter();
#endif
  fleet->add_option("SCENE", fleet_scene, "scene file (.yaml) or MJCF model (.xml)")
      ->required()
      ->check(CLI::ExistingFile);
  fleet->add_option("--steps", fleet_args.steps, "steps per throughput figure (all rounds)")
      ->check(CLI::Range(10, 100000000));
  fleet->add_option("--rounds", fleet_args.rounds, "alternations of bare and measured loops")
      ->check(CLI::Range(1, 1000));
  fleet->add_option("--samples", fleet_args.samples, "round trips per latency figure")
      ->check(CLI::Range(10, 10000000));
  fleet
      ->add_option("--python", fleet_args.python,
                   "the Python interpreter for the Python client (default: $URLAB_PYTHON, else the "
                   "checkout's .venv, else /usr/bin/python3)")
      ->capture_default_str();
  fleet_args.batch_library = BatchLibraryBesideThisProgram();
  fleet
      ->add_option("--batch-library", fleet_args.batch_library,
                   "liburlab_batch.so, for the in-process figures (default: the one beside this "
                   "program, or in its ../lib; \"\": none)")
      ->capture_default_str();
  fleet
      ->add_option("--python-client", fleet_args.python_client,
                   "the folder holding urlab_client (default: this build's clients/python; "
                   "\"\": no Python figures)")
      ->capture_default_str();
  std::vector<std::string> parts;
  std::string part_list;
  for (const auto& [name, produce] : net::FleetFigureProducers()) {
    part_list += (parts.empty() ? "" : ", ") + name;
    parts.push_back(name);
  }
  fleet
      ->add_option("--only", fleet_args.only,
                   "run only these parts, comma-separated (default: all of them, in this "
                   "order): " +
                       part_list)
      ->check(CLI::IsMember(parts))
      ->delimiter(',');
  fleet->callback([&exit_code] {
    CurrentInput() = fleet_scene;
    fleet_args.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
    const std::vector<net::FleetFigure> figures =
        net::RunFleetBench(world::LoadSceneOrModel(fleet_scene), fleet_args);
    for (const net::FleetFigure& f : figures) std::printf("%s=%.4g\n", f.key.c_str(), f.value);
    std::fflush(stdout);
    exit_code = 0;
  });

  CLI::App* cameras = bench->add_subcommand(
      "cameras",
      "Off-screen camera cost: frames per second of one camera (RGB, RGB+depth, segmentation), "
      "the latency from a state to a ZeroMQ subscriber with the camera subsystem streaming "
      "(p50/p99), and the physics loop's rate with the camera rendering at --rate over the loop "
      "without (alternating trials). The last lines are key=value for scripts.");
  static camera::CameraBenchOptions camera_args;
  static std::string camera_scene;
  cameras->add_option("SCENE", camera_scene, "scene file (.yaml) or MJCF model (.xml)")
      ->required()
      ->check(CLI::ExistingFile);
  cameras->add_option("--camera", camera_args.camera,
                      "articulation/camera (default: the first camera of an articulation)");
  cameras->add_option("--width", camera_args.width)->check(CLI::Range(1, 8192));
  cameras->add_option("--height", camera_args.height)->check(CLI::Range(1, 8192));
  cameras->add_option("--rate", camera_args.rate, "streaming rate (Hz)")
      ->check(CLI::Range(0.1, 1000.0));
  cameras->add_option("--seconds", camera_args.fps_seconds, "seconds per fps measurement")
      ->check(CLI::Range(0.1, 60.0));
  cameras->add_option("--trials", camera_args.loop_trials, "loop ratio trials")
      ->check(CLI::Range(1, 100));
  cameras->callback([&exit_code] {
    CurrentInput() = camera_scene;
    camera_args.latency_seconds = std::max(camera_args.fps_seconds, 1.0);
    camera_args.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
    const camera::CameraBenchResult r =
        camera::RunCameraBench(world::LoadSceneOrModel(camera_scene), camera_args);
    std::printf(
        "fps_rgb=%.1f\nfps_rgb_depth=%.1f\nfps_segmentation=%.1f\nlatency_p50_ms=%.2f\n"
        "latency_p99_ms=%.2f\nloop_ratio=%.4f\n",
        r.fps_rgb, r.fps_rgb_depth, r.fps_segmentation, r.latency_p50_ms, r.latency_p99_ms,
        r.loop_ratio);
    std::fflush(stdout);
    exit_code = 0;
  });

  CLI::App* peers = bench->add_subcommand(
      "peers",
      "Environment steps per second of URLab beside the tools a user would pick instead, on one "
      "model file, timestep and frame skip (default: gymnasium's Humanoid, humanoid.xml, "
      "frame skip 5): EnvPool's Humanoid-v5 (envpool, its thread pool of --threads), "
      "gymnasium's Humanoid-v5 in SyncVectorEnv (gym_sync) and AsyncVectorEnv (gym_async, one "
      "process per environment), URLab's in-process batch (urlab_inproc, "
      "UrlabVectorEnv.in_process, "
      "--threads) and batched server (urlab_server: urlab run MODEL --envs N --threads T and "
      "the Python batch client), and physics alone (physics: mujoco.rollout with --threads "
      "threads, row rollout, against URLab's batch step, rows urlab_physics (the library's own "
      "step time) and urlab_physics_wall (Python's wall time), on the same trajectories, "
      "alternating). Random actions in the ctrlranges; episodes end as Humanoid-v5's (torso "
      "height outside (1, 2), 1000 steps), reset noise 0.01. Each (peer, N) runs in its own "
      "Python process (bench/peers.py, the project's Python), --repeats measurements of "
      "--seconds each. Prints one row per (peer, N) with the median, min and max environment "
      "steps per second and the CPU time per step (microseconds, of the peer's threads and "
      "processes: psutil), then key=value lines: versions, <row>_n<N>_env_steps_per_s and "
      "<row>_n<N>_cpu_us_per_env_step, ours_over_envpool (urlab_inproc over envpool at the "
      "largest N, with _min and _max from the two spreads and _cpu, EnvPool's CPU per step over "
      "ours; when EnvPool cannot run, envpool=unavailable reason=..., nearest_peer and "
      "ours_over_nearest instead), server_over_envpool, ours_over_rollout (urlab_physics over "
      "rollout at the largest N, median of the paired repeats, with _min, _max, _wall (Python's "
      "wall time), _cpu (rollout's CPU per step over ours), and _n<N> for the other N), "
      "physics_max_abs_diff (URLab's last state against rollout's "
      "on the same trajectories) and "
      "load_average_1min. Progress goes to stderr.");
  static BenchPeersArgs peers_args;
  peers_args.python = PythonInterpreter();
  peers_args.batch_library = BatchLibraryBesideThisProgram();
  peers_args.python_client = PythonClientDir();
  peers
      ->add_option("MODEL", peers_args.model,
                   "MJCF model every peer steps (default: gymnasium's humanoid.xml)")
      ->check(CLI::ExistingFile);
  peers->add_option("--envs", peers_args.envs, "environment counts, comma-separated")
      ->delimiter(',')
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  peers
      ->add_option("--threads", peers_args.threads,
                   "threads of the peers that take threads (EnvPool, mujoco.rollout, URLab)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  peers->add_option("--seconds", peers_args.seconds, "seconds per measurement")
      ->check(CLI::Range(0.01, 600.0))
      ->capture_default_str();
  peers->add_option("--repeats", peers_args.repeats, "measurements per (peer, N)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  peers->add_option("--frame-skip", peers_args.frame_skip, "physics steps per environment step")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  peers
      ->add_option("--skip", peers_args.skip,
                   "peers to leave out, comma-separated: envpool, gym_sync, gym_async, "
                   "urlab_inproc, urlab_server, physics")
      ->delimiter(',')
      ->check(CLI::IsMember(
          {"envpool", "gym_sync", "gym_async", "urlab_inproc", "urlab_server", "physics"}));
  peers
      ->add_option("--python", peers_args.python,
                   "the Python interpreter (default: $URLAB_PYTHON, else the checkout's .venv, "
                   "else /usr/bin/python3)")
      ->capture_default_str();
  peers
      ->add_option("--batch-library", peers_args.batch_library,
                   "liburlab_batch.so (default: the one beside this program, or in its ../lib)")
      ->capture_default_str();
  peers
      ->add_option("--python-client", peers_args.python_client,
                   "the folder holding urlab_client (default: $URLAB_PYTHON_CLIENT, else this "
                   "build's clients/python)")
      ->capture_default_str();
  peers->callback([&exit_code] { exit_code = RunBenchPeers(peers_args); });

  RegisterBenchBatchCommand(*bench, exit_code);
}

}  // namespace urlab::app
