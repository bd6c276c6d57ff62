// Benchmark: composing and compiling 22 humanoids from a scene versus MuJoCo composing the same
// 22 copies itself (mj_parseXML of examples/models/humanoid.xml, each attached to a frame of an
// empty spec with mjs_attach and a prefix, one mj_compile), in the same process (interleaved
// runs, medians). Target: ratio <= 1.15.
// Usage: bench_compose [REPEATS]
#include <mujoco/mujoco.h>

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

namespace {

// What MuJoCo itself does for the same scene: 22 parsed copies attached with prefixes.
void MujocoAttach22() {
  const char* path = URLAB_SOURCE_DIR "/examples/models/humanoid.xml";
  char error[1024] = "";
  mjSpec* root = mj_makeSpec();
  for (int i = 0; i < 22; ++i) {
    mjSpec* child = mj_parseXML(path, nullptr, error, sizeof(error));
    if (!child) {
      std::fprintf(stderr, "%s: %s\n", path, error);
      std::exit(1);
    }
    mjsFrame* frame = mjs_addFrame(mjs_findBody(root, "world"), nullptr);
    frame->pos[0] = 2.0 * (i % 5);
    frame->pos[1] = 2.0 * (i / 5);
    const std::string prefix = "h" + std::to_string(i) + "_";
    if (!mjs_attach(frame->element, child->element, prefix.c_str(), "")) {
      std::fprintf(stderr, "mjs_attach: %s\n", mjs_getError(root));
      std::exit(1);
    }
    mj_deleteSpec(child);
  }
  mjModel* m = mj_compile(root, nullptr);
  if (!m) {
    std::fprintf(stderr, "mj_compile: %s\n", mjs_getError(root));
    std::exit(1);
  }
  mj_deleteModel(m);
  mj_deleteSpec(root);
}

}  // namespace

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  const int repeats = argc > 1 ? std::atoi(argv[1]) : 7;
  std::string yaml = "size: {nconmax: 1000, njmax: 3000}\narticulations:\n";
  for (int i = 0; i < 22; ++i) {
    yaml += "  - name: h" + std::to_string(i) +
            "\n    mjcf: " URLAB_SOURCE_DIR "/examples/models/humanoid.xml\n    pos: [" +
            std::to_string(2.0 * (i % 5)) + ", " + std::to_string(2.0 * (i / 5)) + ", 0]\n" +
            (i ? "    include_world: false\n" : "");
  }
  const urlab::world::SceneConfig scene = urlab::world::ParseScene(yaml, "/tmp/bench_22.yaml");
  std::vector<double> ours, mujoco;
  int nq = 0, nu = 0;
  for (int i = 0; i < repeats; ++i) {
    mujoco.push_back(Seconds([&] { MujocoAttach22(); }));
    ours.push_back(Seconds([&] {
      urlab::world::CompiledScene s = urlab::world::BuildScene(scene);
      nq = s.model->nq;
      nu = s.model->nu;
    }));
  }
  const double o = Median(ours), m = Median(mujoco);
  std::printf("composed nq=%d nu=%d repeats=%d\n", nq, nu, repeats);
  std::printf("urlab_compose_compile_ms=%.2f mjs_attach_22_humanoids_ms=%.2f\n", o * 1e3, m * 1e3);
  std::printf("ratio=%.4f (target <= 1.15)\n", o / m);
  return 0;
}
