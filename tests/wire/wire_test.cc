// The streaming topics' byte layouts against bytes computed by hand from docs/protocol.md's tables,
// and the decoders' refusals (each with its reason).
#include "urlab/wire/wire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace urlab::wire {
namespace {

// "07 00 00 00 ..." -> bytes.
std::string Hex(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    if (text[i] == ' ') {
      ++i;
      continue;
    }
    out.push_back(static_cast<char>(std::stoi(text.substr(i, 2), nullptr, 16)));
    i += 2;
  }
  return out;
}

TEST(WireTest, TopicNames) {
  EXPECT_EQ(JointTopic("go2", "FL_hip"), "go2/joint/FL_hip");
  EXPECT_EQ(BaseStateTopic("go2", "root"), "go2/base_state/root");
  EXPECT_EQ(SensorTopic("arm", "imu_acc"), "arm/sensor/imu_acc");
  EXPECT_EQ(TwistTopic("go2"), "go2/twist");
  EXPECT_EQ(ActionsTopic("go2"), "go2/actions");
  EXPECT_EQ(ControlTopic("go2"), "go2/control ");
  EXPECT_EQ(SetGainsTopic("go2"), "go2/set_gains ");
}

TEST(WireTest, JointIsIdThenThreeFloats) {
  std::string b;
  AppendJoint(&b, 7, 1.0, -2.0, 0.5);
  // int32 7; f32 1.0 = 0x3f800000; -2.0 = 0xc0000000; 0.5 = 0x3f000000 (little-endian).
  EXPECT_EQ(b, Hex("07000000 0000803f 000000c0 0000003f"));
  EXPECT_EQ(b.size(), kJointBytes);
  const auto m = DecodeJoint(b);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->joint_id, 7);
  EXPECT_EQ(m->qvel, std::vector<float>{-2.0f});
}

TEST(WireTest, BallJointIsIdThenTenFloats) {
  const double q[4] = {1, 0, 0, 0}, v[3] = {0.5, 0, -1}, a[3] = {0, 2, 0};
  std::string b;
  AppendBallJoint(&b, 258, q, v, a);
  EXPECT_EQ(b, Hex("02010000 0000803f 00000000 00000000 00000000"
                   "0000003f 00000000 000080bf 00000000 00000040 00000000"));
  EXPECT_EQ(b.size(), kBallJointBytes);
  const auto m = DecodeJoint(b);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->qpos.size(), 4u);
  EXPECT_EQ(m->qacc[1], 2.0f);
}

TEST(WireTest, BaseStatePutsTheQuaternionWLast) {
  // qpos: pos (1, 2, 3), quat w=0.5 x=-0.5 y=0.25 z=1; qvel: lin (0, 0, -1), ang (4, 0, 0).
  const double qpos[7] = {1, 2, 3, 0.5, -0.5, 0.25, 1};
  const double qvel[6] = {0, 0, -1, 4, 0, 0};
  std::string b;
  AppendBaseState(&b, qpos, qvel);
  EXPECT_EQ(b, Hex("0000803f 00000040 00004040"           // pos
                   "000000bf 0000803e 0000803f 0000003f"  // x y z w
                   "00000000 00000000 000080bf"           // linvel
                   "00008040 00000000 00000000"));        // angvel
  const auto m = DecodeBaseState(b);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->quat_wxyz, (std::array<float, 4>{0.5f, -0.5f, 0.25f, 1.0f}));
}

TEST(WireTest, SensorIsIdDimThenValues) {
  const double v[3] = {1, -1, 0.5};
  std::string b;
  AppendSensor(&b, 3, v);
  EXPECT_EQ(b, Hex("03000000 03000000 0000803f 000080bf 0000003f"));
  const auto m = DecodeSensor(b);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->values.size(), 3u);
  EXPECT_FALSE(DecodeSensor(b.substr(0, b.size() - 1)));  // dim says 3, 2.75 values present
  EXPECT_FALSE(DecodeSensor(Hex("03000000 ffffffff")));   // negative dim
}

TEST(WireTest, TwistActionsAndControl) {
  std::string t;
  AppendTwist(&t, 1.0, 0, -0.5);
  EXPECT_EQ(t, Hex("0000803f 00000000 000000bf"));
  std::string a;
  AppendActions(&a, 0b101);
  EXPECT_EQ(a, Hex("05000000"));
  const std::pair<std::int32_t, float> values[] = {{4, 0.5f}, {5, -1.0f}};
  std::string c;
  AppendControl(&c, values);
  EXPECT_EQ(c, Hex("02000000 04000000 0000003f 05000000 000080bf"));
  std::vector<std::pair<std::int32_t, float>> out;
  EXPECT_EQ(DecodeControl(c, &out), std::nullopt);
  EXPECT_EQ(out, (std::vector<std::pair<std::int32_t, float>>{{4, 0.5f}, {5, -1.0f}}));
  EXPECT_EQ(DecodeControl(Hex("00000000"), &out), std::nullopt);  // n = 0 is a valid no-op
  EXPECT_TRUE(out.empty());
}

TEST(WireTest, ControlRefusalsNameTheirReason) {
  std::vector<std::pair<std::int32_t, float>> out;
  EXPECT_EQ(DecodeControl("", &out), Drop::kTruncated);
  EXPECT_EQ(DecodeControl(Hex("0100"), &out), Drop::kTruncated);
  EXPECT_EQ(DecodeControl(Hex("ffffffff"), &out), Drop::kNegativeCount);
  EXPECT_EQ(DecodeControl(Hex("ffffff7f"), &out), Drop::kTooMany);  // INT32_MAX: no overflow
  EXPECT_EQ(DecodeControl(Hex("02000000 04000000 0000003f"), &out), Drop::kTruncated);
  EXPECT_EQ(DecodeControl(Hex("01000000 04000000 0000003f 00"), &out), Drop::kBadSize);
  EXPECT_EQ(DecodeControl(Hex("01000000 04000000 0000c07f"), &out), Drop::kNonFinite);  // NaN
  EXPECT_EQ(DecodeControl(Hex("01000000 04000000 0000807f"), &out), Drop::kNonFinite);  // inf
  EXPECT_TRUE(out.empty());  // nothing partially decoded
  EXPECT_STREQ(DropName(Drop::kForeignActuator), "foreign_actuator");
}

TEST(WireTest, SetGainsIsAPartialPatch) {
  std::vector<GainPatch> out;
  EXPECT_EQ(
      DecodeSetGains(R"({"knee": {"kp": 50}, "go2_hip": {"kv": 2, "torque_limit": 30}})", &out),
      std::nullopt);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].name, "knee");
  EXPECT_EQ(out[0].kp, 50.0);
  EXPECT_FALSE(out[0].kv);
  EXPECT_EQ(out[1].torque_limit, 30.0);
  EXPECT_EQ(DecodeSetGains("{", &out), Drop::kBadJson);
  EXPECT_EQ(DecodeSetGains("[1, 2]", &out), Drop::kBadJson);
  EXPECT_EQ(DecodeSetGains(R"({"knee": 5})", &out), Drop::kBadJson);
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kd": 5}})", &out), Drop::kUnknownField);
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kp": "5"}})", &out), Drop::kBadNumber);
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kp": -1}})", &out), Drop::kBadNumber);
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kp": 1e999}})", &out), Drop::kBadJson);  // overflow
  EXPECT_TRUE(out.empty());
}

// The limits: deeper than an object of objects is refused before parsing (a million levels
// cost a scan, not a parse); a payload beyond kMaxInboundPayloadBytes is not decoded at all.
TEST(WireTest, InboundDecodersHaveSizeAndDepthLimits) {
  std::vector<GainPatch> gains;
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kp": {"x": 1}}})", &gains), Drop::kBadJson);
  const std::string deep = std::string(1000000, '[') + std::string(1000000, ']');
  EXPECT_EQ(DecodeSetGains(deep, &gains), Drop::kTooLarge);
  const std::string deep_small = std::string(200000, '[') + std::string(200000, ']');
  EXPECT_EQ(DecodeSetGains(deep_small, &gains), Drop::kBadJson);
  EXPECT_EQ(DecodeSetGains(R"({"knee": {"kp": 1, "kv": 2}})", &gains), std::nullopt);
  std::vector<std::pair<std::int32_t, float>> values;
  std::string big(kMaxInboundPayloadBytes + 1, '\0');
  EXPECT_EQ(DecodeControl(big, &values), Drop::kTooLarge);
  // The largest control message is exactly at the limit and decodes.
  std::vector<std::pair<std::int32_t, float>> many(kMaxControlCount, {0, 1.0f});
  std::string largest;
  AppendControl(&largest, many);
  ASSERT_EQ(largest.size(), kMaxInboundPayloadBytes);
  EXPECT_EQ(DecodeControl(largest, &values), std::nullopt);
  EXPECT_EQ(values.size(), many.size());
}

}  // namespace
}  // namespace urlab::wire
