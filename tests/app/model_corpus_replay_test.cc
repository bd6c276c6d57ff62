// Every model of the MuJoCo 3.x constructs corpus (tests/data/mjcf/bridge3x), the robot-style
// corpus, the examples' models and, when $URLAB_MUJOCO_MODELS names it, MuJoCo's own corpus (model/
// and test/ of the pinned release, brought by tools/corpus_check), recorded for one second through
// a scene by the real binary (`urlab record MODEL.xml`: a scene of one articulation) and checked
// with `urlab replay FILE --check`: every one re-simulates bit for bit from the MJB the recording
// carries.
//
// No model is excluded. Two models run at a time (the CI machine has 2 cores); each is recorded for
// one simulated second at real-time pacing, so the whole test takes about 20 s plus loading.
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "model_files.h"
#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::SourcePath;
using testing::UrlabBinary;

std::vector<std::string> ModelFiles(const fs::path& root) {
  std::vector<std::string> files;
  if (!fs::is_directory(root)) return files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (!e.is_regular_file() || e.path().extension() != ".xml") continue;
    files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

struct Outcome {
  std::string model;
  int record = -1, check = -1;
  std::string output;
};

Outcome RecordAndCheck(const std::string& model, const std::string& file) {
  Outcome o;
  o.model = model;
  std::string out;
  o.record = RunCommand(UrlabBinary() + " record --ports auto '" + model + "' -o '" + file +
                            "' --duration 1 --no-network --no-cameras",
                        &out);
  o.output = out;
  if (o.record != 0) return o;
  o.check = RunCommand(UrlabBinary() + " replay '" + file + "' --check", &out);
  o.output += out;
  return o;
}

TEST(ModelCorpusReplayTest, EveryBridgeRobotAndExampleModelReSimulatesBitForBit) {
  std::vector<std::string> models = ModelFiles(SourcePath("tests/data/mjcf/bridge3x"));
  const std::size_t bridged = models.size();
  ASSERT_GE(bridged, 10u);
  for (const std::string& dir : {SourcePath("tests/data/mjcf/robots"),
                                 SourcePath("examples/models"), testing::MujocoCorpusDir()}) {
    if (dir.empty()) continue;
    const std::vector<std::string> more = ModelFiles(dir);
    models.insert(models.end(), more.begin(), more.end());
  }

  const std::string dir = testing::MakeTempDir("corpus_replay");
  std::vector<Outcome> outcomes(models.size());
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < models.size(); i = next++) {
      outcomes[i] = RecordAndCheck(models[i], dir + "/" + std::to_string(i) + ".urrec");
    }
  };
  std::thread a(worker), b(worker);
  a.join();
  b.join();

  for (const Outcome& o : outcomes) {
    SCOPED_TRACE(o.model);
    EXPECT_EQ(o.record, 0) << "urlab record failed:\n" << o.output;
    if (o.record != 0) continue;
    EXPECT_EQ(o.check, 0) << o.output;
    EXPECT_NE(o.output.find("re-simulation identical"), std::string::npos) << o.output;
  }
}

}  // namespace
}  // namespace urlab
