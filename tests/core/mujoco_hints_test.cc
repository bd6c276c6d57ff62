#include "urlab/core/mujoco_hints.h"

#include <gtest/gtest.h>

namespace urlab {
namespace {

TEST(MujocoHintsTest, StackOverflowPointsAtMemory) {
  EXPECT_NE(MujocoHint("MuJoCo error: mj_stackAlloc: out of memory, stack overflow at "
                       "mj_instantiateContact, line 1521")
                .find("size: {memory:"),
            std::string::npos);
  EXPECT_NE(MujocoHint("Insufficient arena memory for the constraint solver").find("memory"),
            std::string::npos);
  EXPECT_EQ(MujocoHint("something unheard of"), "");
}

}  // namespace
}  // namespace urlab
