// The grammar's value counts, types and ranges are authoritative in every path: the reader
// refuses a bad value at its file:line, Set() refuses it in code (builder, bridge, composer), and
// typed getters refuse what the grammar would (so callers may index up to the grammar's count).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mujoco_test.h"
#include "urlab/document/document.h"
#include "urlab/document/element.h"
#include "urlab/mjcf/reader.h"

namespace urlab {
namespace {

struct BadValue {
  const char* section;  // element placed in <worldbody> unless "option"/"size"/"compiler"
  const char* element;  // the element with its attribute, written on line 3
  const char* expect;   // fragment of the message
};

// Too few, too many, non-numeric, NaN, ints MuJoCo would misread, out-of-range values.
constexpr BadValue kBad[] = {
    // too few (read past the buffer in composition before)
    {"worldbody", R"(<geom type="capsule" size="0.1" fromto="0 0 0 1 1"/>)",
     "at least 6 numbers, got 5"},
    {"worldbody", R"(<site fromto="1 2 3"/>)", "at least 6 numbers, got 3"},
    {"worldbody", R"(<geom size="1" pos="1 2"/>)", "at least 3 numbers, got 2"},
    {"worldbody", R"(<body quat="1 0 0"><geom size="1"/></body>)", "at least 4 numbers, got 3"},
    {"worldbody", R"(<geom size="1" rgba="1 0 0"/>)", "at least 4 numbers, got 3"},
    {"worldbody", R"(<camera xyaxes="1 0 0 0 1"/>)", "at least 6 numbers, got 5"},
    {"worldbody", R"(<light dir="0 0"/>)", "at least 3 numbers, got 2"},
    {"worldbody", R"(<geom size=""/>)", "at least 1 number, got 0"},
    {"option", R"(<option gravity="0 -9.81"/>)", "at least 3 numbers, got 2"},
    {"compiler", R"(<compiler inertiagrouprange="0"/>)", "at least 2 integers, got 1"},
    // too many
    {"worldbody", R"(<geom size="1" pos="1 2 3 4"/>)", "at most 3 numbers, got 4"},
    {"worldbody", R"(<geom size="1 2 3 4"/>)", "at most 3 numbers, got 4"},
    {"worldbody", R"(<geom size="1" friction="1 1 1 1"/>)", "at most 3 numbers, got 4"},
    {"option", R"(<option timestep="0.01 0.02"/>)", "at most 1 number, got 2"},
    // not numbers
    {"worldbody", R"(<geom size="1" pos="1 two 3"/>)", "is not a list of numbers"},
    {"worldbody", R"(<geom size="1" pos="1,2,3"/>)", "is not a list of numbers"},
    {"worldbody", R"(<geom size="1" pos="nan 0 0"/>)", "contains NaN"},
    // infinity, refused like NaN (2.2.2 would compile an infinite geom)
    {"worldbody", R"(<geom size="inf"/>)", "contains an infinite value"},
    {"worldbody", R"(<geom size="1" pos="0 -inf 0"/>)", "contains an infinite value"},
    {"worldbody", R"(<body><joint range="-1 INF"/><geom size="1"/></body>)", "infinite"},
    // ints: MuJoCo's strtol would read "5e+06" as 5 and "0x10" as 0
    {"size", R"(<size nstack="5e+06"/>)", "plain decimal digits"},
    {"size", R"(<size nuserdata="0x10"/>)", "plain decimal digits"},
    {"size", R"(<size njmax="1.5"/>)", "plain decimal digits"},
    {"size", R"(<size nconmax="99999999999"/>)", "out of the range of an int"},
    {"worldbody", R"(<geom size="1" condim="3.0"/>)", "plain decimal digits"},
    // ranges
    {"option", R"(<option timestep="0"/>)", "timestep': 0 is out of range (expected > 0"},
    {"option", R"(<option timestep="-0.001"/>)", "out of range"},
    {"option", R"(<option timestep="inf"/>)", "out of range"},
    {"option", R"(<option iterations="-1"/>)", "out of range"},
    {"size", R"(<size nstack="-2"/>)", "out of range"},
};

std::string Model(const BadValue& b) {
  const std::string s = b.section;
  if (s == "worldbody") {
    return std::string("<mujoco>\n  <worldbody>\n    ") + b.element +
           "\n  </worldbody>\n</mujoco>\n";
  }
  return std::string("<mujoco>\n  <worldbody/>\n  ") + b.element + "\n</mujoco>\n";
}

class ValueCheckTest : public testing::MujocoTest {};

TEST_F(ValueCheckTest, TheReaderRefusesEveryBadValueAtItsLine) {
  const std::string dir = testing::MakeTempDir("values");
  for (const BadValue& b : kBad) {
    const std::string path = dir + "/m.xml";
    try {
      mjcf::ReadString(Model(b), path);
      ADD_FAILURE() << "accepted: " << b.element;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().file, path) << b.element;
      EXPECT_EQ(e.where().line, 3) << b.element << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find(b.expect), std::string::npos)
          << b.element << ": " << e.what();
    }
  }
}

TEST_F(ValueCheckTest, GoodValuesAtTheBoundsPass) {
  const std::string dir = testing::MakeTempDir("values_ok");
  EXPECT_NO_THROW(mjcf::ReadString(R"(<mujoco>
  <option timestep="1e-6" iterations="0" gravity=" 0 0 -9.81 "/>
  <size nstack="-1" njmax="+100" nconmax="2147483647"/>
  <worldbody>
    <geom type="capsule" size="0.1" fromto="0 0 0 1 1 1" rgba="1 1 1 1" condim="-0"/>
    <geom size="1 2 3" friction="1" pos="1e3 -2 3.5e-2"/>
  </worldbody>
</mujoco>
)",
                                   dir + "/m.xml"));
}

TEST_F(ValueCheckTest, SetRefusesWhatTheGrammarRefuses) {
  document::Document doc;
  document::Element& geom = doc.Section("worldbody").AddChild("geom");
  EXPECT_THROW(geom.Set("fromto", "0 0 0 1 1"), InputError);
  EXPECT_THROW(geom.Set("pos", "1 2 3 4"), InputError);
  EXPECT_THROW(doc.Section("size").Set("nstack", "5e+06"), InputError);
  EXPECT_THROW(doc.Section("option").SetReal("timestep", 0), InputError);
  EXPECT_THROW(doc.Section("option").SetReal("timestep", std::nan("")), InputError);
  EXPECT_THROW(geom.SetReal("size", std::numeric_limits<double>::infinity()), InputError);
  EXPECT_NO_THROW(geom.Set("fromto", "0 0 0 1 1 1"));
  // A whole number is written in plain digits, so an int attribute reads it back as itself.
  doc.Section("size").SetReal("nstack", 5000000);
  EXPECT_EQ(*doc.Section("size").Get("nstack"), "5000000");
  EXPECT_EQ(document::FormatReal(5e6), "5000000");
  EXPECT_EQ(document::FormatReal(0.1), "0.1");
  EXPECT_EQ(document::FormatReal(1e20), "1e+20");
}

TEST_F(ValueCheckTest, TypedGettersRefuseWrongCountsWithTheElementsLocation) {
  document::Document doc;
  document::Element& geom = doc.Section("worldbody").AddChild("geom");
  geom.set_location({"robot.xml", 12});
  // Raw attributes (as a reader or a bridge copies them) bypass Set's check; getters still refuse.
  geom.AddRawAttribute("fromto", "0 0 0 1 1");
  geom.AddRawAttribute("condim", "3.5");
  geom.AddRawAttribute("priority", "4000000000");
  try {
    geom.GetReals("fromto");
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "robot.xml:12");
    EXPECT_NE(std::string(e.what()).find("at least 6"), std::string::npos) << e.what();
  }
  EXPECT_THROW(geom.GetInt("condim"), InputError);
  EXPECT_THROW(geom.GetInt("priority"), InputError);
  geom.AddRawAttribute("pos", "1 2 3");
  EXPECT_THROW(geom.GetReals("pos", 4), InputError);
  EXPECT_EQ(geom.GetReals("pos", 3)->size(), 3u);
}

}  // namespace
}  // namespace urlab
