// The scene of robots written like Unitree's and Menagerie's files
// (examples/scenes/unitree_style.yaml) through the real binary: `validate`, `run` and
// `bench loop` all take it, and `validate` and `run` agree, on the good scene and on a broken
// copy of it.
#include <filesystem>
#include <fstream>
#include <regex>

#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::SourcePath;
using testing::UrlabBinary;

const std::string kScene = "examples/scenes/unitree_style.yaml";

// "nq 25, nv 24, nu 17" from validate; "nq=25, nu=17" from run.
int SizeAfter(const std::string& out, const std::string& key) {
  std::smatch m;
  if (!std::regex_search(out, m, std::regex(key + "[ =]([0-9]+)"))) return -1;
  return std::stoi(m[1]);
}

TEST(UnitreeSceneTest, ValidatesRunsAndAgrees) {
  std::string validated, ran;
  ASSERT_EQ(RunCommand(UrlabBinary() + " validate " + SourcePath(kScene), &validated), 0)
      << validated;
  EXPECT_NE(validated.find(": OK,"), std::string::npos) << validated;
  EXPECT_EQ(validated.find("warning"), std::string::npos) << validated;
  // No network: other tests (ctest -j) play scenes on the default ports at the same time, and a
  // port in use is logged as an error.
  ASSERT_EQ(RunCommand(UrlabBinary() + " run --ports auto " + SourcePath(kScene) +
                           " --duration 3 --no-network",
                       &ran),
            0)
      << ran;
  // The same model: the sizes validate compiled are the ones run plays.
  EXPECT_EQ(SizeAfter(validated, "nq"), 25) << validated;
  EXPECT_EQ(SizeAfter(validated, "nu"), 17) << validated;
  EXPECT_EQ(SizeAfter(ran, "nq"), SizeAfter(validated, "nq")) << ran;
  EXPECT_EQ(SizeAfter(ran, "nu"), SizeAfter(validated, "nu")) << ran;
  std::smatch steps;
  ASSERT_TRUE(
      std::regex_search(ran, steps, std::regex(R"(summary: sim_time=[0-9.]+ s steps=([0-9]+))")))
      << ran;
  EXPECT_GT(std::stoi(steps[1]), 500) << ran;
  EXPECT_EQ(ran.find("diverge"), std::string::npos) << ran;
  EXPECT_EQ(ran.find("error"), std::string::npos) << ran;
}

TEST(UnitreeSceneTest, BenchLoopRunsIt) {
  std::string out;
  ASSERT_EQ(
      RunCommand(UrlabBinary() + " bench loop " + SourcePath(kScene) + " --steps 2000 --trials 2",
                 &out),
      0)
      << out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(\nratio=([0-9.]+)\s*$)"))) << out;
  EXPECT_GT(std::stod(m[1]), 0.0) << out;
}

// A copy of the scene whose quadruped lost a mesh file: validate and run both refuse it and both
// name the missing file.
TEST(UnitreeSceneTest, ValidateAndRunRefuseTheSameBrokenScene) {
  const std::string dir = testing::MakeTempDir("unitree_broken");
  fs::copy(SourcePath("tests/data/mjcf/robots/go2"), dir + "/go2", fs::copy_options::recursive);
  fs::remove(dir + "/go2/assets/meshes/calf.obj");
  const std::string scene = testing::WriteTextFile(dir, "scene.yaml",
                                                   "articulations:\n"
                                                   "  - name: dog\n"
                                                   "    mjcf: go2/scene.xml\n"
                                                   "    keyframe: home\n");
  std::string validated, ran;
  EXPECT_NE(RunCommand(UrlabBinary() + " validate " + scene, &validated), 0) << validated;
  EXPECT_NE(RunCommand(UrlabBinary() + " run --ports auto " + scene + " --duration 1", &ran), 0)
      << ran;
  EXPECT_NE(validated.find("calf.obj"), std::string::npos) << validated;
  EXPECT_NE(ran.find("calf.obj"), std::string::npos) << ran;
  EXPECT_NE(validated.find("go2.xml:"), std::string::npos) << validated;
  EXPECT_NE(ran.find("go2.xml:"), std::string::npos) << ran;
}

}  // namespace
}  // namespace urlab
