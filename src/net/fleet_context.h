#pragma once
// What a figure producer of `urlab bench fleet` (urlab/net/fleet_bench.h) may use: the options,
// the served simulation's step-server endpoint and articulation, a bare mj_step rate on a copy of
// its model, and per-round ratio bookkeeping.
//
// Thread: main (the bench's), like the producers.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "urlab/net/fleet_bench.h"

namespace urlab::net {

class FleetContext {
 public:
  FleetContext(const FleetBenchOptions& options, std::string rpc, std::string articulation,
               const mjModel* bare_model, mjData* bare_data)
      : options_(options),
        rpc_(std::move(rpc)),
        articulation_(std::move(articulation)),
        m_(bare_model),
        d_(bare_data) {}

  const FleetBenchOptions& options() const { return options_; }
  const std::string& rpc() const { return rpc_; }
  const std::string& articulation() const { return articulation_; }
  int steps_per_round() const { return std::max(10, options_.steps / options_.rounds); }

  // Steps per second of `steps` bare mj_step calls (continuing from the bare copy's state).
  double BareRate(int steps);
  // Every BareRate of the run so far, in order: how much the same loop's speed moved.
  const std::vector<double>& bare_rates() const { return bare_rates_; }
  // Aggregate steps per second of `threads` plain threads, each stepping `steps` times its own
  // copy of the bare copy's state (its own mjData, the shared model only read), with no
  // synchronisation between them (one start signal; the wall time runs from it to the last
  // thread's end): what the machine's cores give at all, with no batch around them. With
  // `copies` > 1 each thread steps that many copies in turn (`steps` in all): what the cores give
  // to that many separate simulations per thread (each one's data leaves the caches before its
  // next step), still with no batch around them.
  double CeilingRate(int threads, int steps, int copies = 1);
  // Median over rounds of measure() / BareRate measured just before it (each round). With
  // sync_bare set, each round's bare loop first takes the served simulation's state, so that it
  // steps exactly the trajectory the measured loop steps next (a lying humanoid's step costs
  // more or less with its contacts: two states apart are two different workloads).
  double MedianRatio(const std::function<double()>& measure);
  // Copies the served simulation's current state into the bare copy (set by the bench; the
  // served simulation waits for lockstep requests between the figures, so it is still then).
  std::function<void(mjData*)> sync_bare;

  // The work of a batched figure, to time the same physics without a batch around it (a
  // humanoid's step under random actions costs more than one under none: the bare loop's work
  // is not the batch's). `envs` environments each start from the reset state and step `warm`
  // then `steps` times, environment e's i-th step (counted from 0 within each part) with the
  // action row actions[((i / hold) % sets) * envs + e] (nu values): each action held for `hold`
  // steps (a client's n_steps per request: frame skip).
  struct Trajectories {
    int envs = 0, nu = 0, sets = 0, warm = 0, steps = 0, hold = 1;
    std::vector<double> actions;  // sets x envs x nu, row-major
  };
  // `sets` action sets drawn uniformly from a fixed seed within each actuator's ctrlrange (an
  // unlimited actuator: [-1, 1]).
  Trajectories MakeTrajectories(int envs, int sets, int warm, int steps, std::uint64_t seed,
                                int hold = 1) const;
  // Timed steps per second of the trajectories on `threads` plain threads (environment e on
  // thread e % threads, each its own mjData), counting only the `steps` part. One by one: each
  // thread runs one environment's trajectory to its end, then the next, on one mjData (one
  // thread: the bare single-thread loop doing the batch's work). In turn: each thread keeps an
  // mjData per environment and steps them one after another, step by step, as a batch does
  // (their data leaves the caches between a simulation's steps): the ceiling of that batch on
  // that many cores (the wall time from one start signal to the last thread's end).
  double TrajectoryRate(const Trajectories& t, int threads, bool in_turn = false);
  // The reset state of the served simulation (as a batched server resets an environment: the
  // model's defaults, then each articulation's initial keyframe); default: mj_resetData.
  std::function<void(const mjModel*, mjData*)> reset_state;
  void Report(const std::string& line) const {
    if (options_.report) options_.report(line);
  }
  std::string scene_path;  // the scene file (a producer may start its own `urlab run` of it)

 private:
  const FleetBenchOptions& options_;
  std::string rpc_, articulation_;
  const mjModel* m_;
  mjData* d_;
  std::vector<double> bare_rates_;
};

// The stepping threads of the batched server's figures and of the ceiling.
constexpr int kFleetBatchThreads = 2;

// The batched server's figures (fleet_batch_bench.cc).
void BatchFigures(FleetContext& ctx, std::vector<FleetFigure>* out);
void DaskFigures(FleetContext& ctx, std::vector<FleetFigure>* out);
// The same 64 environments inside the Python script's process (fleet_batch_bench.cc).
void InProcessFigures(FleetContext& ctx, std::vector<FleetFigure>* out);
// Dask rollout workers, each stepping in-process environments with a policy it is sent
// (fleet_batch_bench.cc).
void RolloutFigures(FleetContext& ctx, std::vector<FleetFigure>* out);

}  // namespace urlab::net
