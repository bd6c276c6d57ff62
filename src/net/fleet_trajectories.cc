// FleetContext's batch-matched bare loops (fleet_context.h): the physics of a batched figure
// timed without the batch, so that its ratio compares the same work.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <random>
#include <thread>

#include "net/fleet_context.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab::net {

FleetContext::Trajectories FleetContext::MakeTrajectories(int envs, int sets, int warm, int steps,
                                                          std::uint64_t seed, int hold) const {
  if (envs < 1 || sets < 1 || warm < 0 || steps < 1 || hold < 1) {
    throw Error("bench fleet: trajectories need envs, sets, steps and hold >= 1");
  }
  Trajectories t{.envs = envs,
                 .nu = static_cast<int>(m_->nu),
                 .sets = sets,
                 .warm = warm,
                 .steps = steps,
                 .hold = hold};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  t.actions.resize(static_cast<std::size_t>(sets) * static_cast<std::size_t>(envs) *
                   static_cast<std::size_t>(m_->nu));
  for (std::size_t k = 0; k < t.actions.size(); ++k) {
    const int a = static_cast<int>(k % static_cast<std::size_t>(m_->nu));
    const bool limited = m_->actuator_ctrllimited[a] != 0;
    const double lo = limited ? m_->actuator_ctrlrange[2 * a] : -1.0;
    const double hi = limited ? m_->actuator_ctrlrange[2 * a + 1] : 1.0;
    t.actions[k] = lo + (hi - lo) * unit(rng);
  }
  return t;
}

double FleetContext::TrajectoryRate(const Trajectories& t, int threads, bool in_turn) {
  using Clock = std::chrono::steady_clock;
  threads = std::clamp(threads, 1, t.envs);
  const std::size_t nu = static_cast<std::size_t>(t.nu);
  const auto reset = [&](mjData* d) {
    if (reset_state) {
      reset_state(m_, d);
    } else {
      mj_resetData(m_, d);
    }
  };
  // Environment e's i-th step (counted within its warm-up and its timed part alike).
  const auto act = [&](mjData* d, int e, int i) {
    const std::size_t row = static_cast<std::size_t>((i / t.hold % t.sets) * t.envs + e);
    std::copy_n(t.actions.data() + row * nu, nu, d->ctrl);
    mj_step(m_, d);
  };
  std::vector<double> seconds(static_cast<std::size_t>(threads), 0.0);
  std::atomic<bool> go{false};
  const auto run = [&](int k) {
    // Thread k's environments and their data (one mjData reused one by one; one each in turn).
    std::vector<int> envs;
    for (int e = k; e < t.envs; e += threads) envs.push_back(e);
    std::vector<physics::DataPtr> datas;
    for (std::size_t j = 0; j < (in_turn ? envs.size() : 1); ++j) {
      datas.push_back(physics::MakeData(m_));
    }
    while (!go.load(std::memory_order_acquire)) std::this_thread::yield();
    double timed = 0;
    if (in_turn) {
      for (std::size_t j = 0; j < envs.size(); ++j) reset(datas[j].get());
      for (int i = 0; i < t.warm; ++i) {
        for (std::size_t j = 0; j < envs.size(); ++j) act(datas[j].get(), envs[j], i);
      }
      const auto t0 = Clock::now();
      for (int i = 0; i < t.steps; ++i) {
        for (std::size_t j = 0; j < envs.size(); ++j) act(datas[j].get(), envs[j], i);
      }
      timed = std::chrono::duration<double>(Clock::now() - t0).count();
    } else {
      mjData* d = datas.front().get();
      for (const int e : envs) {
        reset(d);
        for (int i = 0; i < t.warm; ++i) act(d, e, i);
        const auto t0 = Clock::now();
        for (int i = 0; i < t.steps; ++i) act(d, e, i);
        timed += std::chrono::duration<double>(Clock::now() - t0).count();
      }
    }
    seconds[static_cast<std::size_t>(k)] = timed;
  };
  std::vector<std::thread> workers;
  for (int k = 1; k < threads; ++k) workers.emplace_back(run, k);
  go.store(true, std::memory_order_release);
  run(0);
  for (std::thread& w : workers) w.join();
  // Each thread's timed seconds: the threads start together and step the same number of
  // environments (give or take one), so the slowest one's time is the wall time of the work.
  const double wall = *std::max_element(seconds.begin(), seconds.end());
  return static_cast<double>(t.envs) * t.steps / wall;
}

}  // namespace urlab::net
