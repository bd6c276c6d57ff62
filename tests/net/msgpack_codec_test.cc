// msgpack through msgpack-cxx: requests decoded under limits (hand-made bytes, including
// hostile headers), values and observations encoded directly and read back by another decoder
// (nlohmann's), and the observation written the same way for msgpack and JSON clients.
#include "net/msgpack_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "net/observation.h"
#include "support/mujoco_test.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab::net {
namespace {

using namespace std::string_literals;  // the bytes below hold NULs

std::optional<Json> Decode(const std::string& bytes, std::string* why) {
  return DecodeMsgpack(bytes.data(), bytes.size(), why);
}

TEST(MsgpackDecodeTest, ReadsAMapOfEveryKind) {
  // {"op": "step", "n": 3, "neg": -2, "x": 1.5, "ok": true, "nil": nil, "a": [1, 2], "b": bin}
  const std::string bytes =
      "\x88"
      "\xa2op\xa4step"
      "\xa1n\x03"
      "\xa3neg\xfe"
      "\xa1x\xcb\x3f\xf8\x00\x00\x00\x00\x00\x00"s
      "\xa2ok\xc3"
      "\xa3nil\xc0"
      "\xa1"
      "a\x92\x01\x02"
      "\xa1"
      "b\xc4\x02\xab\xcd"s;
  std::string why;
  const std::optional<Json> j = Decode(bytes, &why);
  ASSERT_TRUE(j) << why;
  EXPECT_EQ((*j)["op"], "step");
  EXPECT_EQ((*j)["n"], 3);
  EXPECT_EQ((*j)["neg"], -2);
  EXPECT_EQ((*j)["x"], 1.5);
  EXPECT_EQ((*j)["ok"], true);
  EXPECT_TRUE((*j)["nil"].is_null());
  EXPECT_EQ((*j)["a"], Json::array({1, 2}));
  ASSERT_TRUE((*j)["b"].is_binary());
  EXPECT_EQ((*j)["b"].get_binary().size(), 2u);
}

TEST(MsgpackDecodeTest, RefusesHostileBytesWithAReason) {
  struct Case {
    std::string bytes, reason;
  };
  const Case cases[] = {
      {""s, "truncated"},
      {"\x82\xa2op", "truncated"},                          // a map cut short
      {"\x81\xa2op\xa4step\x00"s, "trailing bytes"},        // one value, then more
      {"\x81\x01\x02", "map keys must be strings"},         // {1: 2}
      {"\x81\xa1x\xd4\x01\x00"s, "ext values"},             // an ext value
      {"\xdd\xff\xff\xff\xff", "larger than the message"},  // array32 of 4 billion items
      {"\xdf\xff\xff\xff\xff", "larger than the message"},  // map32 likewise
      {"\xdb\xff\xff\xff\xff", "truncated"},  // str32 of 4 GiB: waits for bytes that never come
      {"\xc6\x7f\xff\xff\xff", "truncated"},  // bin32 of 2 GiB likewise
      {"\xc1", "parse error"},                // never-used byte
  };
  for (const Case& c : cases) {
    std::string why;
    EXPECT_FALSE(Decode(c.bytes, &why)) << c.reason;
    EXPECT_NE(why.find(c.reason), std::string::npos) << "got: " << why;
  }
  // Nested arrays deeper than the limit.
  std::string deep(kMaxMsgpackDepth + 8, '\x91');
  deep += '\x01';
  std::string why;
  EXPECT_FALSE(Decode(deep, &why));
  EXPECT_NE(why.find("deep"), std::string::npos) << why;
}

TEST(MsgpackWriterTest, EncodesTheProtocolsBytesExactly) {
  MsgpackWriter w;
  w.Map(2);
  w.Key("op");
  w.Str("ok");
  w.Key("v");
  w.Doubles(std::array<double, 1>{1.0}.data(), 1, false);
  const std::string expect = "\x82\xa2op\xa2ok\xa1v\x91\xcb\x3f\xf0\x00\x00\x00\x00\x00\x00"s;
  EXPECT_EQ(std::string(w.data(), w.size()), expect);
  w.Clear();
  const double two[] = {1.0, -2.0};
  w.Doubles(two, 2, true);  // bin8 of 16 little-endian f64 bytes
  ASSERT_EQ(w.size(), 18u);
  EXPECT_EQ(static_cast<unsigned char>(w.data()[0]), 0xc4);
  EXPECT_EQ(static_cast<unsigned char>(w.data()[1]), 16);
  double back[2];
  std::memcpy(back, w.data() + 2, 16);
  EXPECT_EQ(back[0], 1.0);
  EXPECT_EQ(back[1], -2.0);
}

TEST(MsgpackWriterTest, AnyJsonValueRoundTripsThroughAnotherDecoder) {
  const Json v = {{"op", "hello_ok"},
                  {"int", -7},
                  {"big", std::numeric_limits<std::uint64_t>::max()},
                  {"real", 0.25},
                  {"list", {1, "two", nullptr, false}},
                  {"nested", {{"a", {{"b", Json::array()}}}}},
                  {"bin", Json::binary({1, 2, 3})}};
  MsgpackWriter w;
  w.Value(v);
  const auto* p = reinterpret_cast<const std::uint8_t*>(w.data());
  EXPECT_EQ(Json::from_msgpack(p, p + w.size()), v);
  std::string why;
  const std::optional<Json> ours = DecodeMsgpack(w.data(), w.size(), &why);
  ASSERT_TRUE(ours) << why;
  EXPECT_EQ(*ours, v);
}

// The observation is one layout whichever encoding carries it.
class ObservationTest : public urlab::testing::MujocoTest {};

TEST_F(ObservationTest, MsgpackAndJsonCarryTheSameMapAtEveryLevel) {
  const std::string dir = urlab::testing::MakeTempDir("observation");
  urlab::testing::WriteTextFile(dir, "arm.xml", R"(<mujoco>
  <worldbody>
    <body name="base" pos="0 0 1">
      <freejoint name="root"/>
      <geom type="box" size="0.1 0.1 0.1" mass="1"/>
      <body name="link">
        <joint name="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="m" joint="hinge"/></actuator>
  <sensor><jointpos name="angle" joint="hinge"/><framepos name="where" objtype="body" objname="link"/></sensor>
</mujoco>
)");
  const std::shared_ptr<world::Session> session = world::Session::Create(
      world::ParseScene("articulations:\n  - {name: arm, mjcf: arm.xml}\n", dir + "/scene.yaml"));
  const std::vector<ArticulationTopics> tables = BuildTopicTables(*session);
  auto sub = session->engine().SubscribeState("test");  // not started: the current state
  const physics::StateFrame& f = *sub->Latest();
  for (const ObsLevel level : {ObsLevel::kMinimal, ObsLevel::kStandard, ObsLevel::kFull}) {
    for (const bool binary : {false, true}) {
      MsgpackWriter w;
      w.Map(kObservationEntries);
      WriteObservationEntries(w, tables, f, level, binary);
      const auto* p = reinterpret_cast<const std::uint8_t*>(w.data());
      Json packed = Json::from_msgpack(p, p + w.size());
      Json tree = Observation(tables, f, level, binary);
      packed.erase("wall_time");  // read from the clock at each call
      tree.erase("wall_time");
      EXPECT_EQ(packed, tree) << static_cast<int>(level) << " binary " << binary;
      const Json& arm = tree["per_articulation"]["arm"];
      EXPECT_EQ(arm.contains("ctrl"), level != ObsLevel::kMinimal);
      EXPECT_EQ(arm.contains("xpos"), level == ObsLevel::kFull);
      if (!binary) {
        EXPECT_EQ(arm["qpos"].size(), 8u);  // free base 7 + hinge 1
      }
    }
  }
}

}  // namespace
}  // namespace urlab::net
