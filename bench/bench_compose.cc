// Benchmark: composing and compiling 22 humanoids from a scene versus MuJoCo's own mj_loadXML of
// /usr/share/mujoco/model/humanoid/22_humanoids.xml, in the same process (interleaved runs,
// medians). Target: ratio <= 1.15.
// Usage: bench_compose [REPEATS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_util.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/world/scene.h"

using urlab::bench::Median;
using urlab::bench::Seconds;

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  const int repeats = argc > 1 ? std::atoi(argv[1]) : 7;
  std::string yaml = "size: {nconmax: 1000, njmax: 3000}\narticulations:\n";
  for (int i = 0; i < 22; ++i) {
    yaml += "  - name: h" + std::to_string(i) +
            "\n    mjcf: /usr/share/mujoco/model/humanoid/humanoid.xml\n    pos: [" +
            std::to_string(2.0 * (i % 5)) + ", " + std::to_string(2.0 * (i / 5)) + ", 0]\n" +
            (i ? "    include_world: false\n" : "");
  }
  const urlab::world::SceneConfig scene = urlab::world::ParseScene(yaml, "/tmp/bench_22.yaml");
  std::vector<double> ours, mujoco;
  int nq = 0, nu = 0;
  for (int i = 0; i < repeats; ++i) {
    mujoco.push_back(Seconds(
        [&] { urlab::physics::LoadXmlFile("/usr/share/mujoco/model/humanoid/22_humanoids.xml"); }));
    ours.push_back(Seconds([&] {
      urlab::world::CompiledScene s = urlab::world::BuildScene(scene);
      nq = s.model->nq;
      nu = s.model->nu;
    }));
  }
  const double o = Median(ours), m = Median(mujoco);
  std::printf("composed nq=%d nu=%d repeats=%d\n", nq, nu, repeats);
  std::printf("urlab_compose_compile_ms=%.2f mj_loadXML_22_humanoids_ms=%.2f\n", o * 1e3, m * 1e3);
  std::printf("ratio=%.4f (target <= 1.15)\n", o / m);
  return 0;
}
