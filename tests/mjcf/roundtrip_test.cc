// Round trip: import then export every model of MuJoCo's corpus ($URLAB_MUJOCO_MODELS) and the
// hand-written corpus; the output, loaded from another working directory, must give a model of the
// same sizes whose 1000-step zero-control trajectory is bit-identical to the original's.
#include <filesystem>

#include "model_files.h"
#include "mujoco_test.h"
#include "urlab/mjcf/reader.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"
#include "urlab/physics/trajectory_compare.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> ModelFiles() {
  return testing::ModelFilesIn({testing::MujocoCorpusDir(), URLAB_TEST_DATA_DIR "/mjcf/corpus"});
}

class RoundTripTest : public testing::MujocoTest,
                      public ::testing::WithParamInterface<std::string> {};

TEST_P(RoundTripTest, BitIdenticalTrajectoryFromAnotherDirectory) {
  const std::string path = GetParam();
  physics::ModelPtr original;
  try {
    original = physics::LoadXmlFile(path);
  } catch (const physics::CompileError&) {
    GTEST_SKIP() << "not a standalone model (MuJoCo itself does not load it): " << path;
  }
  // Warnings of the original load are the model's own; the reload must give the same ones.
  const std::vector<std::string> original_warnings = TakeWarnings();

  const std::string out_dir = testing::MakeTempDir("roundtrip");
  const std::string out = out_dir + "/" + fs::path(path).filename().string();
  document::Document doc = mjcf::ReadFile(path);
  mjcf::WriteFile(doc, out);

  const std::string elsewhere = testing::MakeTempDir("cwd");
  const fs::path old_cwd = fs::current_path();
  fs::current_path(elsewhere);
  physics::ModelPtr reloaded;
  try {
    reloaded = physics::LoadXmlFile(out);
  } catch (...) {
    fs::current_path(old_cwd);
    throw;
  }
  fs::current_path(old_cwd);
  EXPECT_EQ(TakeWarnings(), original_warnings);

  EXPECT_EQ(physics::CompareSizes(original.get(), reloaded.get()), "") << path;
  EXPECT_EQ(physics::CompareTrajectories(original.get(), reloaded.get(), 1000), "") << path;
}

INSTANTIATE_TEST_SUITE_P(AllModels, RoundTripTest, ::testing::ValuesIn(ModelFiles()),
                         testing::ModelTestName);

}  // namespace
}  // namespace urlab
