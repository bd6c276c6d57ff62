#include "net/latency_request.h"

#include <gtest/gtest.h>

#include <string>

#include "urlab/ops/error.h"

namespace urlab::net {
namespace {

TEST(LatencyRequestTest, SimClockIsTakenAndAWallClockIsRefusedSayingWhyAndWhatToUse) {
  const physics::LatencySetting s =
      LatencySettingFromRequest(Json{{"delay_s", 0.05}, {"clock", "sim"}}, "cameras.rig/front");
  EXPECT_EQ(s.delay, 0.05);
  EXPECT_FALSE(s.delay_in_steps);
  for (const Json& clock : {Json("wall"), Json(1)}) {
    try {
      LatencySettingFromRequest(Json{{"delay_s", 0.05}, {"clock", clock}}, "cameras.rig/front");
      FAIL() << "clock " << clock.dump() << " was taken";
    } catch (const ops::OpError& e) {
      EXPECT_EQ(e.code, "bad_value");
      const std::string& m = e.message;
      EXPECT_NE(m.find("cameras.rig/front.clock"), std::string::npos) << m;  // the field
      EXPECT_NE(m.find(clock.is_string() ? "\"wall\"" : "number"), std::string::npos) << m;
      EXPECT_NE(m.find("simulated time"), std::string::npos) << m;  // why
      EXPECT_NE(m.find("bit for bit"), std::string::npos) << m;
      EXPECT_NE(m.find("delay_steps"), std::string::npos) << m;  // what to use instead
      EXPECT_NE(m.find("\"sim\""), std::string::npos) << m;
    }
  }
}

}  // namespace
}  // namespace urlab::net
