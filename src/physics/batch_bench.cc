#include "urlab/physics/batch_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "urlab/core/error.h"
#include "urlab/physics/batch.h"

namespace urlab::physics {

namespace {

using SteadyClock = std::chrono::steady_clock;

double Action(int step, int u) { return 0.4 * std::sin(0.05 * step + u); }

// Steps per second of one mjData running `episodes` episodes of `steps` steps from reset; `last`
// gets the final qpos and qvel.
double Bare(const mjModel* m, int episodes, int steps, std::vector<double>* last) {
  DataPtr data = MakeData(m);
  mjData* d = data.get();
  const auto t0 = SteadyClock::now();
  for (int e = 0; e < episodes; ++e) {
    mj_resetData(m, d);
    mj_forward(m, d);
    for (int s = 0; s < steps; ++s) {
      for (int u = 0; u < m->nu; ++u) d->ctrl[u] = Action(s, u);
      mj_step(m, d);
    }
  }
  const double seconds = std::chrono::duration<double>(SteadyClock::now() - t0).count();
  last->assign(d->qpos, d->qpos + m->nq);
  last->insert(last->end(), d->qvel, d->qvel + m->nv);
  return static_cast<double>(episodes) * steps / seconds;
}

// Aggregate environment steps per second of a batch of `envs` running `steps` steps from reset.
double Batched(Batch& batch, int steps, std::vector<double>* last) {
  const mjModel* m = batch.model();
  batch.ResetAll(0);
  std::vector<double> actions(static_cast<std::size_t>(batch.envs() * m->nu));
  std::vector<double> obs(static_cast<std::size_t>(batch.envs() * batch.observation_size()));
  const auto t0 = SteadyClock::now();
  for (int s = 0; s < steps; ++s) {
    for (int i = 0; i < batch.envs(); ++i) {
      for (int u = 0; u < m->nu; ++u)
        actions[static_cast<std::size_t>(i * m->nu + u)] = Action(s, u);
    }
    batch.Step(actions, obs);
  }
  const double seconds = std::chrono::duration<double>(SteadyClock::now() - t0).count();
  // The last environment's qpos and qvel (its row starts with them).
  const double* row =
      obs.data() + (obs.size() - static_cast<std::size_t>(batch.observation_size()));
  last->assign(row, row + m->nq + m->nv);
  return static_cast<double>(batch.envs()) * steps / seconds;
}

}  // namespace

std::vector<BatchBenchPoint> RunBatchBench(const Model& model, const BatchBenchOptions& options) {
  if (options.trials < 1) throw Error("batch bench: trials must be at least 1");
  if (options.threads < 1) throw Error("batch bench: threads must be at least 1");
  std::vector<BatchBenchPoint> points;
  const auto report = [&](const std::string& line) {
    if (options.report) options.report(line);
  };
  for (int n : options.envs) {
    if (n < 1) throw Error("batch bench: envs must be at least 1 (got " + std::to_string(n) + ")");
    BatchBenchPoint p;
    p.envs = n;
    p.steps = std::max(options.min_steps, options.env_steps / n);
    BatchOptions bo;
    bo.envs = n;
    bo.threads = options.threads;
    Batch batch(model, bo);
    std::vector<double> bare_last, batch_last;
    for (int t = 0; t < options.trials; ++t) {
      const double bare = Bare(model.get(), n, p.steps, &bare_last);
      const double batched = Batched(batch, p.steps, &batch_last);
      p.bare_rate = std::max(p.bare_rate, bare);
      p.batch_rate = std::max(p.batch_rate, batched);
      report(fmt::format("N={} K={} trial {}: bare {:.0f} steps/s, batch {:.0f} env-steps/s", n,
                         batch.threads(), t + 1, bare, batched));
    }
    p.identical =
        bare_last.size() == batch_last.size() &&
        std::memcmp(bare_last.data(), batch_last.data(), bare_last.size() * sizeof(double)) == 0;
    p.ratio = p.batch_rate / p.bare_rate;
    points.push_back(p);
  }
  return points;
}

}  // namespace urlab::physics
