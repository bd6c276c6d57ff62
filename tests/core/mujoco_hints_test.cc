#include "urlab/core/mujoco_hints.h"

#include <gtest/gtest.h>

namespace urlab {
namespace {

TEST(MujocoHintsTest, StackOverflowPointsAtNstack) {
  EXPECT_NE(
      MujocoHint("physics loop paused after an error: MuJoCo error: Stack overflow").find("nstack"),
      std::string::npos);
  EXPECT_NE(
      MujocoHint("Pre-allocated contact buffer is full. Increase nconmax above 3.").find("nconmax"),
      std::string::npos);
  EXPECT_EQ(MujocoHint("something unheard of"), "");
}

}  // namespace
}  // namespace urlab
