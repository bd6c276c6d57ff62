// `urlab bench batch`: batched environments (physics::Batch) against a bare mj_step loop.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "app/commands.h"
#include "urlab/physics/batch_bench.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"

namespace urlab::app {

void RegisterBenchBatchCommand(CLI::App& bench, int& exit_code) {
  CLI::App* batch = bench.add_subcommand(
      "batch",
      "Aggregate environment steps per second of N copies of the scene (one model, N mjData) "
      "stepped in lockstep by K threads through the step core, divided by a bare single-thread "
      "mj_step loop doing the same work (N episodes of the same length one after another, same "
      "actions); trials alternate, best of each. Prints key=value lines last: "
      "bare_steps_per_s_N<n>, batch_steps_per_s_N<n>, ratio_N<n>.");
  static std::string scene;
  static physics::BatchBenchOptions options;
  batch->add_option("SCENE", scene, "scene file (.yaml) or MJCF model (.xml)")
      ->required()
      ->check(CLI::ExistingFile);
  batch->add_option("--envs", options.envs, "environment counts to measure (default 1,16,64,256)")
      ->delimiter(',')
      ->check(CLI::Range(1, 100000));
  batch->add_option("--threads", options.threads, "stepping threads (the caller and K-1 workers)")
      ->check(CLI::Range(1, 1024));
  batch
      ->add_option("--steps", options.env_steps,
                   "environment steps per trial (each environment runs steps/N, at least 50)")
      ->check(CLI::Range(1, 100000000));
  batch->add_option("--trials", options.trials, "trials (best of)")->check(CLI::Range(1, 1000));
  batch->callback([&exit_code] {
    CurrentInput() = scene;
    // Exactly what begin-play builds and checks.
    const world::CompiledScene compiled = world::BuildCheckedScene(world::LoadSceneOrModel(scene));
    options.report = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
    std::printf("scene %s: nq=%d nv=%d nu=%d, %d threads\n", scene.c_str(),
                static_cast<int>(compiled.model->nq), static_cast<int>(compiled.model->nv),
                static_cast<int>(compiled.model->nu), options.threads);
    for (const physics::BatchBenchPoint& p : physics::RunBatchBench(compiled.model, options)) {
      std::printf("bare_steps_per_s_N%d=%.0f\nbatch_steps_per_s_N%d=%.0f\nratio_N%d=%.4f\n", p.envs,
                  p.bare_rate, p.envs, p.batch_rate, p.envs, p.ratio);
      if (!p.identical) std::printf("identical_N%d=0\n", p.envs);
    }
    std::fflush(stdout);
    exit_code = 0;
  });
}

}  // namespace urlab::app
