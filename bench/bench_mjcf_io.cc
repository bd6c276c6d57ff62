// Benchmark: URLab's import + export of an MJCF file versus MuJoCo's own mj_loadXML of the same
// file, measured in the same process (interleaved runs, medians). Target: ratio <= 0.10.
// Usage: bench_mjcf_io [MODEL.xml] [REPEATS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_util.h"
#include "urlab/core/mujoco_handlers.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

using urlab::bench::Median;
using urlab::bench::Seconds;

int main(int argc, char** argv) {
  urlab::InstallMujocoHandlers();
  const std::string path = argc > 1 ? argv[1] : URLAB_SOURCE_DIR "/examples/models/humanoid.xml";
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 15;
  std::vector<double> ours, mujoco;
  size_t bytes = 0;
  for (int i = 0; i < repeats; ++i) {
    mujoco.push_back(Seconds([&] { urlab::physics::LoadXmlFile(path); }));
    ours.push_back(Seconds([&] {
      urlab::document::Document doc = urlab::mjcf::ReadFile(path);
      bytes = urlab::mjcf::WriteString(doc).size();
    }));
  }
  const double o = Median(ours), m = Median(mujoco);
  std::printf("model=%s repeats=%d exported_bytes=%zu\n", path.c_str(), repeats, bytes);
  std::printf("urlab_import_export_ms=%.3f mj_loadXML_ms=%.3f\n", o * 1e3, m * 1e3);
  std::printf("ratio=%.4f (target <= 0.10)\n", o / m);
  return 0;
}
