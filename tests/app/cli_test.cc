// End-to-end tests of the `urlab` command-line tool: real binary, real files.
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

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
  EXPECT_NE(out.find("MuJoCo 2.2.2"), std::string::npos) << out;
}

TEST(CliTest, EverySubcommandHasHelp) {
  for (const char* sub : {"", "mjcf", "mjcf roundtrip", "compile"}) {
    std::string out;
    EXPECT_EQ(RunCommand(UrlabBinary() + " " + sub + " --help", &out), 0) << sub << out;
    EXPECT_NE(out.find("Usage:"), std::string::npos) << sub;
  }
}

TEST(CliTest, CompileJsonPrintsSizes) {
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " --log-level off compile --json "
                                       "/usr/share/mujoco/model/humanoid/humanoid.xml",
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
  fs::create_directories(dir + "/sub");
  std::string out;
  ASSERT_EQ(RunCommand(UrlabBinary() + " compile /usr/share/mujoco/model/mug/mug.xml --save-xml " +
                           xml + " --save-mjb " + mjb,
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
                           " mjcf roundtrip /usr/share/mujoco/model/humanoid100/"
                           "humanoid100.xml -o " +
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
  EXPECT_NE(out.find("unknown element"), std::string::npos) << out;
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

}  // namespace
}  // namespace urlab
