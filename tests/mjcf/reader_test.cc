// Reader behaviour: includes, unknown attributes kept, errors with file and line.
#include "urlab/mjcf/reader.h"

#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "urlab/mjcf/writer.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

class ReaderTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("reader"); }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  // Reads `path` expecting an InputError; returns it.
  InputError ExpectError(const std::string& path) {
    try {
      mjcf::ReadFile(path);
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "no error reading " << path;
    return InputError({}, "");
  }
  std::string dir_;
};

TEST_F(ReaderTest, ReadsAndKeepsAttributeTextExactly) {
  const std::string p = Write("m.xml", R"(<mujoco model="m">
  <worldbody>
    <body name="b" pos=" 0 0   1e-0">
      <joint name="j" type="hinge" axis="0 1 0"/>
      <geom type="capsule" size=".05" fromto="0 0 0  .5 0 0"/>
    </body>
  </worldbody>
</mujoco>)");
  document::Document doc = mjcf::ReadFile(p);
  const document::Element* body = doc.FindNamed(document::Namespace::kBody, "b");
  ASSERT_NE(body, nullptr);
  EXPECT_EQ(*body->Get("pos"), " 0 0   1e-0");
  EXPECT_EQ(body->location().line, 3);
  EXPECT_FALSE(body->edited());
  const std::string out = mjcf::WriteString(doc);
  EXPECT_NE(out.find(R"(pos=" 0 0   1e-0")"), std::string::npos) << out;
  physics::CompileXmlString(out);
}

TEST_F(ReaderTest, UnknownAttributeIsKeptVerbatimWithDiagnostic) {
  const std::string p = Write("m.xml", R"(<mujoco>
  <worldbody>
    <body name="b"><joint name="j" frobnicate="-1 1"/><geom size="1"/></body>
  </worldbody>
</mujoco>)");
  document::Document doc = mjcf::ReadFile(p);
  ASSERT_EQ(doc.diagnostics().size(), 1u);
  EXPECT_EQ(doc.diagnostics()[0].where.line, 3);
  EXPECT_NE(doc.diagnostics()[0].message.find("frobnicate"), std::string::npos);
  EXPECT_NE(mjcf::WriteString(doc).find(R"(frobnicate="-1 1")"), std::string::npos);
}

TEST_F(ReaderTest, IncludeIsRelativeToMainFileAndErrorsNameTheIncludedFile) {
  Write("parts/body.xml", R"(<mujoco>
  <body name="inc">
    <geom size="0.1" materiall="x"/>
  </body>
</mujoco>)");
  const std::string bad_attr_ok = Write("main.xml", R"(<mujoco>
  <worldbody>
    <include file="parts/body.xml"/>
  </worldbody>
</mujoco>)");
  // Unknown attribute inside the included file: kept, reported at the included file's line.
  document::Document doc = mjcf::ReadFile(bad_attr_ok);
  ASSERT_EQ(doc.diagnostics().size(), 1u);
  EXPECT_EQ(fs::path(doc.diagnostics()[0].where.file).filename(), "body.xml");
  EXPECT_EQ(doc.diagnostics()[0].where.line, 3);

  Write("parts/bad.xml", "<mujoco>\n  <body name=\"x\">\n    <geomm/>\n  </body>\n</mujoco>\n");
  const std::string main2 = Write("main2.xml", R"(<mujoco>
  <worldbody>
    <include file="parts/bad.xml"/>
  </worldbody>
</mujoco>)");
  InputError e = ExpectError(main2);
  EXPECT_EQ(fs::path(e.where().file).filename(), "bad.xml");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_NE(std::string(e.what()).find("unknown element <geomm>"), std::string::npos) << e.what();
}

TEST_F(ReaderTest, CyclicAndRepeatedIncludesAreErrors) {
  Write("a.xml", "<mujoco>\n  <include file=\"b.xml\"/>\n</mujoco>\n");
  Write("b.xml", "<mujoco>\n\n  <include file=\"a.xml\"/>\n</mujoco>\n");
  const std::string main = Write("main.xml", "<mujoco>\n  <include file=\"a.xml\"/>\n</mujoco>\n");
  InputError e = ExpectError(main);
  EXPECT_NE(std::string(e.what()).find("include cycle"), std::string::npos) << e.what();
  EXPECT_EQ(fs::path(e.where().file).filename(), "b.xml");
  EXPECT_EQ(e.where().line, 3);

  Write("c.xml", "<mujoco>\n  <option timestep=\"0.01\"/>\n</mujoco>\n");
  const std::string twice =
      Write("twice.xml",
            "<mujoco>\n  <include file=\"c.xml\"/>\n  <include file=\"c.xml\"/>\n</mujoco>\n");
  e = ExpectError(twice);
  EXPECT_NE(std::string(e.what()).find("more than once"), std::string::npos) << e.what();
  EXPECT_EQ(e.where().line, 3);
}

TEST_F(ReaderTest, BrokenInputsGiveFileAndLine) {
  struct Case {
    const char* text;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {"<mujoco>\n  <worldbody>\n    <body>\n  </worldbody>\n</mujoco>\n", 0, "malformed XML"},
      {"<mujoco>\n  <worldbody>\n    <bodyy/>\n  </worldbody>\n</mujoco>\n", 3,
       "unknown element <bodyy>"},
      {"<mujoco>\n  <worldbody>\n    <geom size=\"1 x\"/>\n  </worldbody>\n</mujoco>\n", 3,
       "not a list of numbers"},
      {"<mujoco>\n  <worldbody>\n    <geom type=\"sphere2\" size=\"1\"/>\n  "
       "</worldbody>\n</mujoco>\n",
       3, "invalid keyword"},
      {"<mujoco>\n  <worldbody>\n    <geom pos=\"1 2 3 4\" size=\"1\"/>\n  "
       "</worldbody>\n</mujoco>\n",
       3, "at most 3"},
      {"<mujoco>\n  <worldbody>\n    <body><joint name=\"j\"/><geom size=\"1\"/></body>\n"
       "  </worldbody>\n  <actuator>\n    <motor joint=\"nope\"/>\n  </actuator>\n</mujoco>\n",
       6, "no joint named 'nope'"},
      {"<mujoco>\n  <worldbody>\n    <geom size=\"1\" material=\"nope\"/>\n  "
       "</worldbody>\n</mujoco>\n",
       3, "no material named 'nope'"},
      {"<mujoco>\n  <worldbody>\n    <geom size=\"1\" class=\"nope\"/>\n  "
       "</worldbody>\n</mujoco>\n",
       3, "no class named 'nope'"},
      {"<mujoco>\n  <asset>\n    <mesh file=\"missing.stl\"/>\n  </asset>\n</mujoco>\n", 3,
       "not found"},
      {"<mujoco>\n  <include file=\"missing.xml\"/>\n</mujoco>\n", 2, "not found"},
      {"<robot name=\"urdf\"/>\n", 1, "must be <mujoco>"},
      {"", 0, "malformed XML"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string p = Write("broken" + std::to_string(i++) + ".xml", c.text);
    InputError e = ExpectError(p);
    EXPECT_EQ(e.where().file, p) << c.text;
    if (c.line > 0) {
      EXPECT_EQ(e.where().line, c.line) << e.what();
    }
    EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
        << "expected '" << c.message << "' in: " << e.what();
  }
}

}  // namespace
}  // namespace urlab
