#pragma once
// What a figure producer of `urlab bench fleet` (urlab/net/fleet_bench.h) may use: the options,
// the served simulation's step-server endpoint and articulation, a bare mj_step rate on a copy of
// its model, and per-round ratio bookkeeping.
//
// Thread: main (the bench's), like the producers.
#include <mujoco/mujoco.h>

#include <algorithm>
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
  // Aggregate steps per second of `threads` plain threads, each stepping `steps` times its own
  // copy of the bare copy's state (its own mjData, the shared model only read), with no
  // synchronisation between them (one start signal; the wall time runs from it to the last
  // thread's end): what the machine's cores give at all, with no batch around them. With
  // `copies` > 1 each thread steps that many copies in turn (`steps` in all): what the cores give
  // to that many separate simulations per thread (each one's data leaves the caches before its
  // next step), still with no batch around them.
  double CeilingRate(int threads, int steps, int copies = 1);
  // Median over rounds of measure() / BareRate measured just before it (each round).
  double MedianRatio(const std::function<double()>& measure);
  void Report(const std::string& line) const {
    if (options_.report) options_.report(line);
  }
  std::string scene_path;  // the scene file (a producer may start its own `urlab run` of it)

 private:
  const FleetBenchOptions& options_;
  std::string rpc_, articulation_;
  const mjModel* m_;
  mjData* d_;
};

// The stepping threads of the batched server's figures and of the ceiling.
constexpr int kFleetBatchThreads = 2;

// The batched server's figures (fleet_batch_bench.cc).
void BatchFigures(FleetContext& ctx, std::vector<FleetFigure>* out);
void DaskFigures(FleetContext& ctx, std::vector<FleetFigure>* out);

}  // namespace urlab::net
