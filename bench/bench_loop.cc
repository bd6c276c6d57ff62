// Loop overhead benchmark: the full physics loop (PhysicsEngine thread, one humanoid, PD
// controller on every actuator, one pre-step and one post-step callback, as fast as possible)
// against a bare mj_step loop on the same model, in one process (world::RunLoopBench, shared with
// `urlab bench loop`). Prints per-trial rates and `ratio=<full/bare>` last (best trial of each
// loop).
//
// Usage: bench_loop [steps_per_trial=20000] [trials=9] [model=humanoid.xml]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/physics/model.h"
#include "urlab/world/loop_bench.h"

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  urlab::SetLogLevel("warn");
  urlab::world::LoopBenchOptions options;
  options.steps = argc > 1 ? std::atoi(argv[1]) : 20000;
  options.trials = argc > 2 ? std::atoi(argv[2]) : 9;
  const std::string path = argc > 3 ? argv[3] : URLAB_SOURCE_DIR "/examples/models/humanoid.xml";
  options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };

  const urlab::physics::Model model(urlab::physics::LoadXmlFile(path));
  std::printf("model %s\n", path.c_str());
  const urlab::world::LoopBenchResult r = urlab::world::RunLoopBench(model, options);
  std::printf("ratio=%.4f\n", r.ratio);
  return 0;
}
