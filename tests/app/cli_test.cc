// End-to-end tests of the `urlab` command-line tool: real binary, real files.
#include <mujoco/mujoco.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/gcc_workarounds.h"
#include "mujoco_test.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::UrlabBinary;

TEST(CliTest, VersionNamesMujoco) {
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " --version", &out), 0) << out;
  EXPECT_NE(out.find("urlab 0."), std::string::npos) << out;
  EXPECT_NE(out.find("MuJoCo " + std::string(mj_versionString())), std::string::npos) << out;
  EXPECT_NE(out.find("MuJoCo 3."), std::string::npos) << out;
}

TEST(CliTest, EverySubcommandHasHelp) {
  for (const char* sub :
       {"", "mjcf", "mjcf roundtrip", "compile", "validate", "run", "bench", "bench loop"}) {
    std::string out;
    EXPECT_EQ(RunCommand(UrlabBinary() + " " + sub + " --help", &out), 0) << sub << out;
    EXPECT_NE(out.find("Usage:"), std::string::npos) << sub;
  }
}

TEST(CliTest, CompileJsonPrintsSizes) {
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " --log-level off compile --json " URLAB_SOURCE_DIR
                                       "/examples/models/humanoid.xml",
                       &out),
            0)
      << out;
  const auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j.at("nq"), 28);
  EXPECT_EQ(j.at("nv"), 27);
  EXPECT_EQ(j.at("nu"), 21);
  for (const char* k : {"na", "nbody", "njnt", "ngeom", "nsite", "ncam", "nlight", "nmesh", "ntex",
                        "nmat", "ntendon", "nsensor", "nkey", "neq", "npair", "nexclude"}) {
    EXPECT_TRUE(j.contains(k)) << k;
  }
}

TEST(CliTest, CompileSavesLoadableXmlAndMjb) {
  const std::string dir = testing::MakeTempDir("cli_save");
  const std::string xml = dir + "/sub/scene_compiled.xml";
  const std::string mjb = dir + "/scene_compiled.mjb";
  // A model with a file asset next to it (named explicitly: implicitly named file assets are
  // prefixed twice by composition until the composer's fix, issue 7 section 1).
  fs::create_directories(dir + "/assets");
  fs::copy_file(URLAB_TEST_DATA_DIR "/mjcf/robots/arm/assets/link2.obj", dir + "/assets/mug.obj");
  const std::string model = testing::WriteTextFile(dir, "mug.xml", R"(<mujoco>
  <asset><mesh name="mug" file="assets/mug.obj"/></asset>
  <worldbody><body pos="0 0 1"><freejoint/><geom type="mesh" mesh="mug"/></body></worldbody>
</mujoco>
)");
  std::string out;
  ASSERT_EQ(
      RunCommand(UrlabBinary() + " compile " + model + " --save-xml " + xml + " --save-mjb " + mjb,
                 &out),
      0)
      << out;
  ASSERT_TRUE(fs::exists(xml));
  ASSERT_TRUE(fs::exists(mjb));
  std::ifstream in(xml);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Asset paths are relative to the output folder, not absolute.
  EXPECT_NE(text.find("file=\"../"), std::string::npos) << text;
  EXPECT_EQ(text.find("file=\"/usr"), std::string::npos) << text;
  // The saved XML loads on its own, from another working directory.
  ASSERT_EQ(RunCommand("cd / && " + UrlabBinary() + " compile --json " + xml, &out), 0) << out;
}

TEST(CliTest, RoundtripWritesOutput) {
  const std::string dir = testing::MakeTempDir("cli_rt");
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() +
                           " mjcf roundtrip " URLAB_SOURCE_DIR "/examples/models/humanoid.xml -o " +
                           dir + "/h.xml",
                       &out),
            0)
      << out;
  EXPECT_TRUE(fs::exists(dir + "/h.xml"));
}

TEST(CliTest, BrokenModelExitsNonZeroWithFileAndLine) {
  const std::string dir = testing::MakeTempDir("cli_broken");
  const std::string bad = dir + "/bad.xml";
  std::ofstream(bad) << "<mujoco>\n  <worldbody>\n    <bodyy/>\n  </worldbody>\n</mujoco>\n";
  std::string out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " compile " + bad, &out), 1) << out;
  EXPECT_NE(out.find(bad + ":3:"), std::string::npos) << out;
  EXPECT_NE(out.find("unrecognized element"), std::string::npos) << out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " mjcf roundtrip " + bad + " -o " + dir + "/o.xml", &out), 1)
      << out;
  EXPECT_FALSE(fs::exists(dir + "/o.xml"));
}

TEST(CliTest, MujocoCompileErrorIsReportedNotFatal) {
  const std::string dir = testing::MakeTempDir("cli_mjerr");
  const std::string bad = dir + "/bad.xml";
  // Valid grammar, but MuJoCo refuses it (a joint in a body without mass or geoms).
  std::ofstream(bad) << "<mujoco>\n  <worldbody>\n    <body>\n      <joint/>\n    </body>\n"
                        "  </worldbody>\n</mujoco>\n";
  std::string out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " compile " + bad, &out), 1) << out;
  EXPECT_NE(out.find("error"), std::string::npos) << out;
}

TEST(CliTest, ValidateReportsEveryProblem) {
  const std::string dir = testing::MakeTempDir("cli_validate");
  const std::string bad = testing::WriteTextFile(dir, "bad.xml", R"(<mujoco>
  <asset><mesh file="missing.stl"/></asset>
  <worldbody>
    <body name="b"><joint name="j"/><geom size="1" material="nope"/></body>
    <body name="b"><geom size="1"/></body>
  </worldbody>
  <actuator><motor joint="jj"/></actuator>
</mujoco>
)");
  // MuJoCo stops at a file's first problem (the repeated body name, at its line); validate
  // goes on with the scene's other files and its own checks.
  std::string out;
  EXPECT_EQ(RunCommand(UrlabBinary() + " validate " + bad, &out), 1) << out;
  for (const char* want : {"bad.xml:5:", "repeated name 'b'", "1 problem(s)"}) {
    EXPECT_NE(out.find(want), std::string::npos) << want << " missing in:\n" << out;
  }
  const std::string scene =
      testing::WriteTextFile(dir, "s.yaml",
                             "articulations:\n  - {name: a, mjcf: " URLAB_SOURCE_DIR
                             "/examples/models/pendulum_arm.xml}\n  - {name: b, mjcf: bad.xml}\n");
  EXPECT_EQ(RunCommand(UrlabBinary() + " validate " + scene, &out), 1) << out;
  EXPECT_NE(out.find("b: "), std::string::npos) << out;
}

TEST(CliTest, LogsGoToStderrSoJsonStaysClean) {
  std::string out;
  // Logs (the model's composition) go to stderr; stdout must be exactly one JSON object.
  // -O3: a false -Wrestrict inside std::string's operator+ (GCC PR 105329 / 105651).
  URLAB_GCC_IGNORE("-Wrestrict")
  ASSERT_EQ(RunCommand("(" + UrlabBinary() +
                           " compile --json " URLAB_TEST_DATA_DIR
                           "/mjcf/dialect3x/go2_like.xml 2>/dev/null)",
                       &out),
            0)
      << out;
  URLAB_GCC_RESTORE
  EXPECT_EQ(nlohmann::json::parse(out).at("nu"), 12);
}

TEST(CliTest, CompileAcceptsSceneFiles) {
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " --log-level off compile --json " URLAB_SOURCE_DIR
                                       "/examples/scenes/two_arms.yaml",
                       &out),
            0)
      << out;
  EXPECT_EQ(nlohmann::json::parse(out).at("nu"), 4);
}

}  // namespace
}  // namespace urlab
