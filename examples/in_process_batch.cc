// Steps a batch of environments of a scene inside this program (urlab::embed::InProcessBatch: no
// server), with random actions within the actuators' ranges, and prints how many environment
// steps per second it made and how many episodes ended.
// Run: ./build/example_in_process_batch [SCENE] [ENVS] [STEPS]
//      (default: examples/scenes/humanoid_pd.yaml, 64 environments, 500 steps)
#include "urlab/embed/in_process_batch.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "urlab/core/mujoco_handlers.h"

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  const std::string scene = argc > 1 ? argv[1] : "examples/scenes/humanoid_pd.yaml";
  const int envs = argc > 2 ? std::atoi(argv[2]) : 64;
  const int steps = argc > 3 ? std::atoi(argv[3]) : 500;
  try {
    urlab::embed::InProcessBatch batch(scene, {.envs = envs, .max_episode_steps = 200});
    std::vector<std::optional<std::uint64_t>> seeds;
    for (int e = 0; e < batch.envs(); ++e) seeds.push_back(static_cast<std::uint64_t>(e));
    batch.Reset({}, seeds);
    std::mt19937 rng(0);
    std::vector<double> actions(static_cast<std::size_t>(batch.envs() * batch.action_size()));
    int ended = 0;
    const auto start = std::chrono::steady_clock::now();
    for (int s = 0; s < steps; ++s) {
      for (std::size_t i = 0; i < actions.size(); ++i) {
        const std::size_t a = i % static_cast<std::size_t>(batch.action_size());
        const double lo = std::isfinite(batch.action_low()[a]) ? batch.action_low()[a] : -1;
        const double hi = std::isfinite(batch.action_high()[a]) ? batch.action_high()[a] : 1;
        actions[i] = std::uniform_real_distribution<double>(lo, hi)(rng);
      }
      for (std::uint8_t done : batch.Step(actions).done) ended += done;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("%d environments on %d thread(s): %.0f environment steps/s, %d episode(s) ended\n",
                batch.envs(), batch.threads(), steps * batch.envs() / seconds, ended);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
