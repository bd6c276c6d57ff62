#pragma once
// `urlab bench loop --network`: what broadcasting costs the physics loop. Trials alternate
// between the scene played as fast as possible without a network subsystem and the same scene
// with one publishing every streaming topic and state/full on every step to a subscriber that
// takes every message (on loopback, in this process). The ratio is the median loop step rate
// with the network over the median without; the target is at least 0.9.
// Thread: main (it plays its own worlds, one at a time).
#include <functional>
#include <string>
#include <vector>

#include "urlab/world/scene_file.h"

namespace urlab::net {

struct BroadcastBenchOptions {
  int trials = 5;                       // trials per configuration
  double seconds = 1.0;                 // measured time per trial (after a short warm-up)
  std::string full_state = "standard";  // the state/full level broadcast
  int subscriber_nice = 10;             // the subscriber thread's nice value (0: unchanged)
  std::function<void(const std::string&)> report;  // report lines; empty: silent
};

struct BroadcastBenchResult {
  std::vector<double> bare_rates, network_rates;  // steps per second, per trial
  double messages_per_step = 0;  // messages the subscriber received per physics step
  double ratio = 0;              // median network rate / median bare rate
};

BroadcastBenchResult RunBroadcastBench(world::SceneConfig scene,
                                       const BroadcastBenchOptions& options);

}  // namespace urlab::net
