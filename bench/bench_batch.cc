// Batched environments: a physics::Batch of N humanoids stepped by K threads through the step
// core, against a bare single-thread mj_step loop doing the same work, in one process
// (physics::RunBatchBench, shared with `urlab bench batch`). Prints per-trial rates, then
// key=value lines: bare_steps_per_s_N<n>, batch_steps_per_s_N<n>, ratio_N<n> (batch / bare).
//
// Usage: bench_batch [threads=2] [env_steps_per_trial=20000] [trials=5] [model=humanoid.xml]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "urlab/core/mujoco_handlers.h"
#include "urlab/physics/batch_bench.h"
#include "urlab/physics/model.h"

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  urlab::SetLogLevel("warn");
  urlab::physics::BatchBenchOptions options;
  options.threads = argc > 1 ? std::atoi(argv[1]) : 2;
  options.env_steps = argc > 2 ? std::atoi(argv[2]) : 20000;
  options.trials = argc > 3 ? std::atoi(argv[3]) : 5;
  const std::string path = argc > 4 ? argv[4] : URLAB_SOURCE_DIR "/examples/models/humanoid.xml";
  options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  const urlab::physics::Model model(urlab::physics::LoadXmlFile(path));
  std::printf("model %s, %d threads\n", path.c_str(), options.threads);
  for (const auto& p : urlab::physics::RunBatchBench(model, options)) {
    std::printf("bare_steps_per_s_N%d=%.0f\nbatch_steps_per_s_N%d=%.0f\nratio_N%d=%.4f\n", p.envs,
                p.bare_rate, p.envs, p.batch_rate, p.envs, p.ratio);
    if (!p.identical) std::printf("identical_N%d=0\n", p.envs);
  }
  return 0;
}
