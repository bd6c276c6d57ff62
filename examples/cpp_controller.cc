// A C++ controller driving a running simulator over the network (examples/scenes/arm_network.yaml):
//   ./build/urlab run examples/scenes/arm_network.yaml &
//   ./build/example_cpp_controller [tcp://127.0.0.1:5559] [steps]
// It takes the step server's lease, switches to lockstep, swings the arm's shoulder along a sine
// (PD targets, one request per 10 ms of simulated time) and prints the tracking error.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "urlab/client/client.h"

int main(int argc, char** argv) {
  const std::string endpoint = argc > 1 ? argv[1] : "tcp://127.0.0.1:5559";
  const int requests = argc > 2 ? std::atoi(argv[2]) : 500;
  try {
    urlab::client::StepClient sim(endpoint);
    sim.SetMode("direct");
    urlab::client::Observation o = sim.Reset();
    double worst = 0;
    for (int i = 0; i < requests; ++i) {
      const double target = 0.6 * std::sin(2 * M_PI * 0.5 * o.time);
      o = sim.Step(5, {{"arm", {target, -0.3}}});
      const double error = std::abs(o.per_articulation.at("arm").qpos.at(0) - target);
      if (i > requests / 5) worst = std::max(worst, error);  // after the start-up transient
      if (i % 100 == 0) {
        std::printf("t=%.2f s  shoulder %+.3f  target %+.3f\n", o.time,
                    o.per_articulation.at("arm").qpos.at(0), target);
      }
    }
    std::printf("done: %d lockstep requests, worst tracking error %.3f rad\n", requests, worst);
    sim.SetMode("live");  // give the simulation back to real time
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "example_cpp_controller: %s\n", e.what());
    return 1;
  }
}
