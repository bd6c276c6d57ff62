#pragma once
// `urlab bench latency`: what a client sees of the network, against raw ZeroMQ on the same
// machine in the same run. Measures, over real sockets on loopback:
// - streaming: a control message in, until the state/full message that shows it comes out;
// - lockstep: a step request with n_steps=1 and a control, until its reply;
// - raw PUB/SUB and REQ/REP ping-pong through an echo thread (the floor for each kind);
// - lockstep throughput (steps per second through the step server, n=1 and n=10) against a bare
//   mj_step loop on the same model.
// The machine is shared and noisy, so raw and URLab samples alternate in rounds (the engine
// paused while a raw floor is sampled) and each throughput ratio is taken within its round.
// The scene's first articulation is played with passthrough control (so the control shows in
// the state unchanged), as fast as possible. Thread: main (it runs its own world).
#include <functional>
#include <string>

#include "urlab/world/scene_file.h"

namespace urlab::net {

struct LatencyBenchOptions {
  int samples = 2000;                              // round trips per measurement
  int throughput_steps = 20000;                    // steps per throughput measurement (all rounds)
  int rounds = 5;                                  // alternations of raw/bare and URLab samples
  std::function<void(const std::string&)> report;  // report lines; empty: silent
};

struct Percentiles {
  double p50_us = 0, p99_us = 0;
};

struct LatencyBenchResult {
  Percentiles streaming, lockstep, raw_pubsub, raw_reqrep;
  double lockstep_rate_n1 = 0, lockstep_rate_n10 = 0, bare_rate = 0;  // medians, steps/s
  double throughput_ratio_n1 = 0, throughput_ratio_n10 = 0;           // median of per-round ratios
  // The best ratio any lockstep server could reach over this transport: n bare steps plus one
  // raw REQ/REP round trip (p50) per request, against n bare steps.
  double ceiling_n1 = 0, ceiling_n10 = 0;
  // Steps per second when a client keeps several step requests in flight (a DEALER socket):
  // what the server processes, without a round trip per request; median ratio to bare.
  double pipelined_ratio_n1 = 0, pipelined_ratio_n10 = 0;
};

LatencyBenchResult RunLatencyBench(world::SceneConfig scene, const LatencyBenchOptions& options);

}  // namespace urlab::net
