// `urlab bench fleet`'s batched figures: a batched server (`urlab run SCENE --envs N --threads 2`,
// its own process, announced on free ports) driven through the Python vector env
// (UrlabVectorEnv.over_batch, shared memory) at N = 1, 16, 64, 256: aggregate environment steps
// per second through Python, the server's own rate (its physics thread's time on batch steps,
// batch_info's busy_seconds), and their ratios to the bare single-thread loop of the same run.
// batch64_ratio is the Python rate at N = 64 over the bare loop (synchronous step() over one
// server); python_overhead64 is 1 - Python rate / server rate at N = 64; batch64_of_ceiling is
// the Python rate at N = 64 over the same round's rate of 2 independent threads stepping their
// own copies (CeilingRate). Then the same 64 environments as two servers of 32 with one thread
// each: batch2x32_sync_ratio (step()) and batch2x32_async_ratio (send/recv, pipelined).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "net/bench_util.h"
#include "net/fleet_context.h"
#include "urlab/core/error.h"

namespace urlab::net {

namespace {

using bench::Format;
using bench::Median;

// The actions the batched scripts step with (after they made `env`): the sets
// FleetContext::MakeTrajectories drew, from the file argv[4] (float64, sets x n x nu), so that the
// bare loop of the same round times the same physics (BatchWork).
constexpr const char* kFileActions = R"PY(
n, nu = env.num_envs, env.single_action_space.shape[0]
actions = np.fromfile(sys.argv[4], dtype="<f8").reshape(-1, n, nu)
)PY";

// One batched server's vector env: `steps` synchronous steps of n_steps physics steps each (the
// action held: frame skip); prints the Python rate and the server's own (batch_info's busy
// time), in physics steps per second.
constexpr const char* kBatchHead = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from urlab_client import UrlabVectorEnv
endpoint, steps, n_steps = sys.argv[2], int(sys.argv[3]), int(sys.argv[5])
env = UrlabVectorEnv.over_batch(endpoint, frame_skip=n_steps)
client = env.envs[0].client
)PY";
constexpr const char* kBatchBody = R"PY(env.reset(seed=0)
for i in range(10):
    env.step(actions[i % len(actions)])
before = client.call("batch_info")
t0 = time.perf_counter()
for i in range(steps):
    env.step(actions[i % len(actions)])
elapsed = time.perf_counter() - t0
after = client.call("batch_info")
server = (after["env_steps"] - before["env_steps"]) / (after["busy_seconds"] - before["busy_seconds"])
print("rate=%f server=%f transport=%s" % (steps * n * n_steps / elapsed, server, client.transport))
env.close()
)PY";

// The same vector env over 64 environments stepped inside the script's own process
// (UrlabVectorEnv.in_process: URLab's C library, argv[2]), 2 stepping threads; prints the
// Python rate and the stepping thread's own (the library's step time), in steps per second.
constexpr const char* kInProcessHead = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from urlab_client import UrlabVectorEnv
library, steps, n_steps, scene = sys.argv[2], int(sys.argv[3]), int(sys.argv[5]), sys.argv[6]
env = UrlabVectorEnv.in_process(scene, 64, threads=2, library=library, raw_actions=True)
client = env.envs[0]
)PY";

// The same 64 environments as two servers of 32 (one stepping thread each: 2 threads in all),
// one vector env over both, driven first synchronously (step: both servers step, then Python
// handles both replies) and then asynchronously (send/recv: one server steps its half while
// Python handles the other's reply). Prints both aggregate rates.
constexpr const char* kAsyncHead = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from urlab_client import UrlabVectorEnv
endpoints, steps = sys.argv[2].split(","), int(sys.argv[3])
env = UrlabVectorEnv.over_batch(endpoints)
)PY";
constexpr const char* kAsyncBody = R"PY(env.reset(seed=0)
for i in range(10):
    env.step(actions[i % len(actions)])
t0 = time.perf_counter()
for i in range(steps):
    env.step(actions[i % len(actions)])
sync = steps * n / (time.perf_counter() - t0)
env.reset(seed=0)
env.send(actions[0])
for i in range(10 * len(endpoints)):
    obs, rewards, terminated, truncated, infos = env.recv()
    env.send(actions[i % len(actions)][infos["env_id"]], infos["env_id"])
done, t0 = 0, time.perf_counter()
for i in range(steps * len(endpoints)):
    obs, rewards, terminated, truncated, infos = env.recv()
    done += len(infos["env_id"])
    env.send(actions[i % len(actions)][infos["env_id"]], infos["env_id"])
for _ in endpoints:
    obs, rewards, terminated, truncated, infos = env.recv()
    done += len(infos["env_id"])
print("sync=%f async=%f" % (sync, done / (time.perf_counter() - t0)))
env.close()
)PY";

// Dask LocalCluster: 1 worker, then 2, each running one batched server of 16 environments (one
// stepping thread each), driven as one vector env (urlab_client.cluster). Both runs take the same
// number of vector steps from the same start, so each server simulates the same trajectory in
// both (a run of fixed seconds would stop the faster one elsewhere in its episodes, whose physics
// costs more or less per step). Besides the rates, per vector step: the wall time, the busiest
// server's own stepping time (batch_info's busy_seconds) and the driver thread's CPU time
// (its waits for the replies included).
constexpr const char* kDaskScript = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from distributed import Client, LocalCluster
from urlab_client.cluster import ServerPool
urlab, scene, steps = sys.argv[2], sys.argv[3], int(sys.argv[4])
def run(workers):
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=40) as c, Client(c) as client:
        pool = ServerPool(client, scene, workers, urlab=urlab, envs_per_server=16, threads=1,
                          args=("--no-cameras", "--max-speed", "--raw-actions"))
        with pool.batch_vector_env() as envs:
            envs.reset(seed=0)
            a = np.zeros(envs.action_space.shape)
            for _ in range(20):
                envs.step(a)
            busy = [s.client.call("batch_info")["busy_seconds"] for s in envs.envs]
            cpu, t0 = time.thread_time(), time.perf_counter()
            for _ in range(steps):
                envs.step(a)
            wall, cpu = time.perf_counter() - t0, time.thread_time() - cpu
            busy = max(s.client.call("batch_info")["busy_seconds"] - b
                       for s, b in zip(envs.envs, busy))
            return steps * envs.num_envs / wall, 1e6 * wall / steps, 1e6 * busy / steps, \
                1e6 * cpu / steps
one, two = run(1), run(2)
print("one=%f two=%f" % (one[0], two[0]))
for k, r in (("1", one), ("2", two)):
    print("wall%s=%f busy%s=%f cpu%s=%f" % (k, r[1], k, r[2], k, r[3]))
)PY";

// Dask LocalCluster again, 1 worker then 2, each now a rollout worker (urlab_client.rollout): 16
// environments inside the worker's own process (the in-process library, argv[2]), stepped by the
// worker with the policy each call sends (zero actions, as the vector env's figure), `steps` steps
// a call; the driver only sends calls and gathers trajectories. Prints both aggregate rates and,
// per worker of the 2-worker run, its stepping and CPU time over the wall time.
constexpr const char* kRolloutScript = R"PY(
import sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from distributed import Client, LocalCluster
from urlab_client.rollout import RolloutPool
library, scene, steps, calls = sys.argv[2], sys.argv[3], int(sys.argv[4]), 4
def run(workers):
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=40) as c, Client(c) as client:
        with RolloutPool(client, scene, envs_per_worker=16, threads=1, library=library,
                         raw_actions=True) as pool:
            policy = lambda obs, nu=pool.nu: np.zeros((len(obs["qpos"]), nu))
            pool.run(policy, 20)
            done, stepping, cpu, t0 = 0, [0.0] * workers, [0.0] * workers, time.perf_counter()
            for _ in range(calls):
                for k, r in enumerate(pool.run(policy, steps)):
                    done += r["env_steps"]
                    stepping[k] += r["step_seconds"]
                    cpu[k] += r["cpu_seconds"]
            wall = time.perf_counter() - t0
            return done / wall, [s / wall for s in stepping], [c / wall for c in cpu]
one, two = run(1), run(2)
print("one=%f two=%f" % (one[0], two[0]))
print("stepping=%f cpu=%f" % (min(two[1]), min(two[2])))
)PY";

// The figure after `key=` in `text`.
double Field(const std::string& text, const std::string& key) {
  const auto at = text.find(key + "=");
  if (at == std::string::npos) throw Error("bench fleet: no " + key + " in '" + text + "'");
  return std::stod(text.substr(at + key.size() + 1));
}

// Runs `argv` with its stdout captured (stderr kept); returns the output and the exit status.
std::string RunCaptured(const std::vector<std::string>& argv, int* status) {
  int out[2];
  if (pipe(out) != 0) throw Error("bench fleet: no pipe");
  const pid_t child = fork();
  if (child < 0) throw Error("bench fleet: cannot fork");
  if (child == 0) {
    dup2(out[1], 1);
    close(out[0]);
    close(out[1]);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(out[1]);
  std::string text;
  char buf[256];
  ssize_t got = 0;
  while ((got = read(out[0], buf, sizeof(buf))) > 0)
    text.append(buf, static_cast<std::size_t>(got));
  close(out[0]);
  waitpid(child, status, 0);
  return text;
}

std::string SelfPath() {
  char self[4096] = {};
  const ssize_t len = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (len <= 0) throw Error("bench fleet: cannot find the urlab binary");
  return self;
}

// A batched server process: started announced on free ports, stopped (SIGTERM) on destruction.
class BatchServer {
 public:
  BatchServer(const std::string& scene, int envs, int threads) {
    const std::string self = SelfPath();
    announce_ =
        (std::filesystem::temp_directory_path() /
         ("urlab-bench-batch-" + std::to_string(getpid()) + "-" + std::to_string(envs) + ".json"))
            .string();
    std::filesystem::remove(announce_);
    // Lockstep from the start (--step-mode direct), as --envs > 1 implies: a plain run (--envs 1)
    // would otherwise play by itself at full speed between the clients, on the cores the bare
    // loops of the next round measure.
    const std::vector<std::string> argv = {self,
                                           "run",
                                           scene,
                                           "--envs",
                                           std::to_string(envs),
                                           "--raw-actions",  // the bare loop's raw controls
                                           "--threads",
                                           std::to_string(threads),
                                           "--ports",
                                           "auto",
                                           "--announce",
                                           announce_,
                                           "--no-cameras",
                                           "--step-mode",
                                           "direct",
                                           "--max-speed",
                                           "--duration",
                                           "900"};
    pid_ = fork();
    if (pid_ < 0) throw Error("bench fleet: cannot fork");
    if (pid_ == 0) {
      const int null = open("/dev/null", O_WRONLY);
      if (null >= 0) {
        dup2(null, 1);
        dup2(null, 2);
      }
      std::vector<char*> args;
      for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!std::filesystem::exists(announce_)) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw Error("bench fleet: the batched server (--envs " + std::to_string(envs) +
                    ") exited before announcing");
      }
      if (std::chrono::steady_clock::now() > deadline) {
        throw Error("bench fleet: the batched server did not announce within 120 s");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::ifstream in(announce_);
    rpc_ = nlohmann::json::parse(in).at("endpoints").at("rpc").get<std::string>();
  }
  ~BatchServer() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
    std::error_code ec;
    std::filesystem::remove(announce_, ec);
  }
  const std::string& rpc() const { return rpc_; }

 private:
  pid_t pid_ = -1;
  std::string announce_, rpc_;
};

}  // namespace

namespace {

// Runs a Python benchmark `script` with the client's folder as its first argument and `args`
// after it; its output. Throws Error naming `what` when it fails.
std::string RunClientScript(const FleetContext& ctx, const std::string& script,
                            const std::vector<std::string>& args, const std::string& what) {
  const FleetBenchOptions& o = ctx.options();
  std::vector<std::string> argv = {o.python, "-c", script, o.python_client};
  argv.insert(argv.end(), args.begin(), args.end());
  int status = 0;
  const std::string text = RunCaptured(argv, &status);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw Error("bench fleet: the Python " + what + " failed (" + text + ")");
  }
  return text;
}

// A Dask script's 1- and 2-worker rates (one=, two=): runs it with `args` after the client's
// folder, pushes {key}1x16_env_steps_per_s, {key}2x16_env_steps_per_s, {key}_scaling and
// {key}_of_ceiling (the scaling over what 2 plain threads make of the bare loop right after: the
// bound on this machine at this time, so that a slow second CPU is told from a slow fleet), and
// returns the script's output with the ceiling in *ceiling; "" (reported) when the script failed.
std::string DaskScaling(FleetContext& ctx, const char* script, const std::vector<std::string>& args,
                        const std::string& key, std::vector<FleetFigure>* out, double* ceiling) {
  std::string text;
  try {
    text = RunClientScript(ctx, script, args, key + " script");
  } catch (const Error& e) {
    ctx.Report("no " + key +
               " figures (python3-distributed missing, or the cluster failed): " + e.what());
    return "";
  }
  const double one = Field(text, "one"), two = Field(text, "two");
  out->push_back({key + "1x16_env_steps_per_s", one});
  out->push_back({key + "2x16_env_steps_per_s", two});
  out->push_back({key + "_scaling", two / one});
  *ceiling =
      ctx.MedianRatio([&] { return ctx.CeilingRate(kFleetBatchThreads, ctx.steps_per_round()); });
  out->push_back({key + "_of_ceiling", two / one / *ceiling});
  return text;
}

}  // namespace

void DaskFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  const FleetBenchOptions& o = ctx.options();
  if (o.python_client.empty() || access(o.python.c_str(), X_OK) != 0) return;
  double ceiling = 0;
  const std::string text =
      DaskScaling(ctx, kDaskScript, {SelfPath(), ctx.scene_path, "4000"}, "dask", out, &ceiling);
  if (text.empty()) return;
  const double one = Field(text, "one"), two = Field(text, "two");
  ctx.Report(
      Format("Dask LocalCluster, batched servers of 16 environments: 1 worker %.0f, 2 "
             "workers %.0f env steps/s (%.2f; 2 plain threads made %.2f of the bare loop just "
             "after, so %.3f of that ceiling)",
             one, two, two / one, ceiling, two / one / ceiling));
  for (const char* w : {"1", "2"}) {
    const std::string k(w);
    ctx.Report(
        Format("Dask, %s worker(s), per vector step: %.0f us of wall time, the busiest "
               "server stepping %.0f us, the driver's CPU %.0f us (its waits included)",
               w, Field(text, "wall" + k), Field(text, "busy" + k), Field(text, "cpu" + k)));
  }
}

void RolloutFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  const FleetBenchOptions& o = ctx.options();
  if (o.python_client.empty() || access(o.python.c_str(), X_OK) != 0 || o.batch_library.empty() ||
      access(o.batch_library.c_str(), R_OK) != 0) {
    ctx.Report("no Python client or in-process library: Dask rollout figures left out");
    return;
  }
  // Steps per call: 500 at the default --steps (a call then takes about 0.3 s, and Dask's own
  // cost per call is a few milliseconds).
  const int steps = std::clamp(ctx.steps_per_round() / 8, 20, 500);
  double ceiling = 0;
  const std::string text =
      DaskScaling(ctx, kRolloutScript, {o.batch_library, ctx.scene_path, std::to_string(steps)},
                  "dask_rollout", out, &ceiling);
  if (text.empty()) return;
  const double one = Field(text, "one"), two = Field(text, "two");
  ctx.Report(
      Format("Dask LocalCluster, rollout workers of 16 in-process environments (the driver out "
             "of the step loop): 1 worker %.0f, 2 workers %.0f env steps/s (%.2f; %.3f of what 2 "
             "plain threads made of the bare loop just after)",
             one, two, two / one, two / one / ceiling));
  ctx.Report(
      Format("Dask rollouts, 2 workers: the slower worker stepped %.0f%% of the wall time "
             "and ran Python for %.0f%%",
             100 * Field(text, "stepping"), 100 * (Field(text, "cpu") - Field(text, "stepping"))));
}

// A batched figure's work (FleetContext::Trajectories) and its actions in a file for the Python
// script (removed on destruction).
class BatchWork {
 public:
  // The scripts warm up with this many vector steps before timing.
  static constexpr int kWarm = 10;
  static constexpr int kSets = 8;
  // `steps` vector steps of `hold` physics steps each (the client's n_steps).
  BatchWork(FleetContext& ctx, int envs, int steps, int hold = 1)
      : trajectories_(ctx.MakeTrajectories(envs, kSets, kWarm * hold, steps * hold, 0, hold)),
        path_((std::filesystem::temp_directory_path() /
               ("urlab-bench-actions-" + std::to_string(getpid()) + "-" + std::to_string(envs) +
                "-" + std::to_string(hold) + ".f64"))
                  .string()) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(trajectories_.actions.data()),
              static_cast<std::streamsize>(trajectories_.actions.size() * sizeof(double)));
    if (!out.flush()) throw Error("bench fleet: cannot write " + path_);
  }
  ~BatchWork() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  BatchWork(const BatchWork&) = delete;
  BatchWork& operator=(const BatchWork&) = delete;
  const FleetContext::Trajectories& trajectories() const { return trajectories_; }
  const std::string& path() const { return path_; }

 private:
  FleetContext::Trajectories trajectories_;
  std::string path_;
};

// The physics steps per request of batch64_frameskip5_ratio (gymnasium's MuJoCo humanoid holds
// each action for 5 steps).
constexpr int kFrameSkip = 5;

// One run of the batched script over `server` with `work`'s actions and `n_steps` per request;
// its output (rate=..., server=...).
std::string RunBatchScript(const FleetContext& ctx, const BatchServer& server,
                           const BatchWork& work, int n_steps) {
  const int steps = work.trajectories().steps / n_steps;
  return RunClientScript(
      ctx, std::string(kBatchHead) + kFileActions + kBatchBody,
      {server.rpc(), std::to_string(steps), work.path(), std::to_string(n_steps)},
      "batched client");
}

void BatchFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  const FleetBenchOptions& o = ctx.options();
  if (o.python_client.empty() || access(o.python.c_str(), X_OK) != 0) {
    ctx.Report("no Python client (--python-client): batched figures left out");
    return;
  }
  constexpr int kThreads = kFleetBatchThreads;
  for (const int envs : {1, 16, 64, 256}) {
    BatchServer server(ctx.scene_path, envs, kThreads);
    // About as many environment steps per round as the other figures' steps.
    const int steps = std::clamp(ctx.steps_per_round() / envs * 4, 30, 4000);
    const BatchWork work(ctx, envs, steps);
    // Round by round: the bare loop over the same trajectories, then the Python client; ratios to
    // that round's bare rate.
    std::vector<double> python_ratios, server_ratios, server_rates, overheads, of_ceiling, ceilings,
        costs, bares, skip_ratios;
    // At N = 64, also the same with frame skip (n_steps per request).
    std::optional<BatchWork> skip_work;
    if (envs == 64) skip_work.emplace(ctx, envs, std::max(10, steps / kFrameSkip), kFrameSkip);
    for (int round = 0; round < o.rounds; ++round) {
      const double bare = ctx.TrajectoryRate(work.trajectories(), 1);
      bares.push_back(bare);
      // What the same physics costs beside the zero-control bare loop of the other figures.
      costs.push_back(ctx.BareRate(ctx.steps_per_round()) / bare);
      // At N = 64, also what the threads give the same work at all in this round: 32 simulations
      // each, stepped in turn as the batch steps them.
      const double ceiling =
          envs == 64 ? ctx.TrajectoryRate(work.trajectories(), kThreads, /*in_turn=*/true) : 0;
      const std::string text = RunBatchScript(ctx, server, work, 1);
      const double rate = Field(text, "rate"), server_rate = Field(text, "server");
      python_ratios.push_back(rate / bare);
      server_ratios.push_back(server_rate / bare);
      server_rates.push_back(server_rate);
      overheads.push_back(1 - rate / server_rate);
      if (ceiling > 0) {
        of_ceiling.push_back(rate / ceiling);
        ceilings.push_back(ceiling / bare);
      }
      if (skip_work) {
        // The same 64 environments with each action held for kFrameSkip physics steps (one
        // request each), over a bare loop stepping those trajectories.
        const double skip_bare = ctx.TrajectoryRate(skip_work->trajectories(), 1);
        skip_ratios.push_back(Field(RunBatchScript(ctx, server, *skip_work, kFrameSkip), "rate") /
                              skip_bare);
      }
    }
    const double ratio = Median(python_ratios);
    const std::string n = std::to_string(envs);
    out->push_back({"batch" + n + "_python_ratio", ratio});
    out->push_back({"batch" + n + "_server_ratio", Median(server_ratios)});
    out->push_back({"batch" + n + "_server_env_steps_per_s", Median(server_rates)});
    ctx.Report(
        Format("batched server, %d envs, %d threads: Python vector env %.3f of the bare loop "
               "stepping the same trajectories (%.0f steps/s, each step %.2fx the zero-control "
               "bare loop's cost), the server's own rate %.0f env steps/s (%.3f of that), "
               "Python's share %.3f",
               envs, std::min(kThreads, envs), ratio, Median(bares), Median(costs),
               Median(server_rates), Median(server_ratios), Median(overheads)));
    if (envs == 64) {
      // batch64_ratio: the synchronous Python vector env over this one server of 64.
      out->push_back({"batch64_ratio", ratio});
      out->push_back({"python_overhead64", Median(overheads)});
      out->push_back({"batch64_bare_steps_per_s", Median(bares)});
      out->push_back({"batch64_action_cost", Median(costs)});
      out->push_back({"batch64_ceiling", Median(ceilings)});
      out->push_back({"batch64_of_ceiling", Median(of_ceiling)});
      out->push_back({"batch64_frameskip5_ratio", Median(skip_ratios)});
      ctx.Report(
          Format("batched server, 64 envs: %.3f of what %d plain threads make of the same "
                 "trajectories, each stepping its 32 in turn (%.3f of the bare loop: the ceiling)",
                 Median(of_ceiling), kThreads, Median(ceilings)));
      ctx.Report(
          Format("batched server, 64 envs, each action held for %d physics steps (n_steps "
                 "%d, frame skip): Python vector env %.3f of the bare loop stepping the "
                 "same trajectories",
                 kFrameSkip, kFrameSkip, Median(skip_ratios)));
    }
  }
  // The same 64 environments as two servers of 32 with one stepping thread each.
  BatchServer a(ctx.scene_path, 32, 1), b(ctx.scene_path, 32, 1);
  const int steps = std::clamp(ctx.steps_per_round() / 64 * 4, 30, 4000);
  const BatchWork work(ctx, 64, steps);
  std::vector<double> sync_ratios, async_ratios;
  for (int round = 0; round < o.rounds; ++round) {
    // The synchronous run steps exactly these trajectories; the pipelined one draws the same sets
    // in another order (each reply takes the next set), the same kind of work.
    const double bare = ctx.TrajectoryRate(work.trajectories(), 1);
    const std::string text =
        RunClientScript(ctx, std::string(kAsyncHead) + kFileActions + kAsyncBody,
                        {a.rpc() + "," + b.rpc(), std::to_string(steps), work.path()},
                        "asynchronous batched client");
    sync_ratios.push_back(Field(text, "sync") / bare);
    async_ratios.push_back(Field(text, "async") / bare);
  }
  out->push_back({"batch2x32_sync_ratio", Median(sync_ratios)});
  out->push_back({"batch2x32_async_ratio", Median(async_ratios)});
  ctx.Report(
      Format("64 envs as 2 batched servers of 32, 1 thread each: Python vector env %.3f of the "
             "bare loop stepping the same trajectories with step() (synchronous), %.3f with "
             "send/recv (one server steps while Python handles the other's reply)",
             Median(sync_ratios), Median(async_ratios)));
}

void InProcessFigures(FleetContext& ctx, std::vector<FleetFigure>* out) {
  const FleetBenchOptions& o = ctx.options();
  if (o.python_client.empty() || access(o.python.c_str(), X_OK) != 0) {
    ctx.Report("no Python client (--python-client): in-process figures left out");
    return;
  }
  if (o.batch_library.empty() || access(o.batch_library.c_str(), R_OK) != 0) {
    ctx.Report("no in-process library (--batch-library " + o.batch_library +
               "): in-process figures left out");
    return;
  }
  constexpr int kEnvs = 64;
  const int steps = std::clamp(ctx.steps_per_round() / kEnvs * 4, 30, 4000);
  const BatchWork work(ctx, kEnvs, steps);
  std::vector<double> ratios, overheads, of_ceiling, window_ratios;
  for (int round = 0; round < o.rounds; ++round) {
    // As the batched server's figure: the bare loop over the same trajectories, the ceiling of
    // 2 plain threads stepping them in turn, then the Python vector env.
    const double bare = ctx.TrajectoryRate(work.trajectories(), 1);
    const double ceiling =
        ctx.TrajectoryRate(work.trajectories(), kFleetBatchThreads, /*in_turn=*/true);
    const std::string text =
        RunClientScript(ctx, std::string(kInProcessHead) + kFileActions + kBatchBody,
                        {o.batch_library, std::to_string(steps), work.path(), "1", ctx.scene_path},
                        "in-process vector env");
    const double rate = Field(text, "rate"), window = Field(text, "server");
    ratios.push_back(rate / bare);
    window_ratios.push_back(window / bare);
    overheads.push_back(1 - rate / window);
    of_ceiling.push_back(rate / ceiling);
  }
  out->push_back({"batch64_inproc_ratio", Median(ratios)});
  out->push_back({"batch64_inproc_step_ratio", Median(window_ratios)});
  out->push_back({"inproc_overhead64", Median(overheads)});
  out->push_back({"batch64_inproc_of_ceiling", Median(of_ceiling)});
  ctx.Report(
      Format("in-process batch, 64 envs, 2 threads (UrlabVectorEnv.in_process, no server): "
             "Python vector env %.3f of the bare loop stepping the same trajectories, the "
             "library's own step %.3f, Python's share %.3f, %.3f of the ceiling",
             Median(ratios), Median(window_ratios), Median(overheads), Median(of_ceiling)));
}

}  // namespace urlab::net
