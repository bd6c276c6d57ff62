#pragma once
// `urlab bench fleet`: what driving simulations from learning code costs, as key=value figures,
// each ratio against a bare single-thread mj_step loop measured in the same run (alternating
// round by round on a shared machine). One simulation is served on loopback (the scene's first
// articulation, passthrough control, as fast as possible) and driven in lockstep (direct mode)
// over ZeroMQ and over the shared-memory channel, from C++ and from Python, beside raw ZeroMQ
// and raw shared-memory ping-pongs.
//
// The figures come from a list of producers (FleetFigureProducers): each gets the context (the
// served simulation, the bare rate, the options) and appends its figures; add a producer to add
// figures.
//
// Thread: main (it runs its own world).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "urlab/world/scene_file.h"

namespace urlab::net {

struct FleetBenchOptions {
  int steps = 20000;   // steps per throughput figure (over all rounds)
  int rounds = 5;      // alternations of bare and measured loops (medians reported)
  int samples = 4000;  // round trips per latency figure
  std::string python = "/usr/bin/python3";
  std::string python_client;      // the folder holding urlab_client ("": no Python figures)
  std::string batch_library;      // liburlab_batch.so ("": no in-process figures)
  std::vector<std::string> only;  // producers to run by name (empty: all of them)
  std::function<void(const std::string&)> report;  // report lines; empty: silent
};

struct FleetFigure {
  std::string key;  // printed key=value
  double value = 0;
};

class FleetContext;
using FigureProducer = std::function<void(FleetContext&, std::vector<FleetFigure>*)>;

// The producers `urlab bench fleet` runs, in order, by name.
std::vector<std::pair<std::string, FigureProducer>> FleetFigureProducers();

// Serves `scene`'s first articulation and runs every producer; returns their figures.
std::vector<FleetFigure> RunFleetBench(world::SceneConfig scene, const FleetBenchOptions& options);

}  // namespace urlab::net
