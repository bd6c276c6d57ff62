#include "urlab/physics/free_base.h"

#include <gtest/gtest.h>

#include <string>

#include "support/mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab::physics {
namespace {

// A two-link body under `parent_joint` (empty: welded to the world).
std::string Robot(const std::string& name, const std::string& parent_joint) {
  return "<body name='" + name + "' pos='0 0 1'>" + parent_joint +
         "<geom size='0.1'/>"
         "<body name='" +
         name + "_l1' pos='0 0 0.2'><joint name='" + name +
         "_j1' axis='0 1 0'/><geom size='0.05'/>"
         "<body name='" +
         name + "_l2' pos='0 0 0.2'><joint name='" + name +
         "_j2' axis='0 1 0'/><geom size='0.05'/></body></body></body>";
}

std::string Ball(const std::string& name) {
  return "<body name='" + name + "' pos='1 0 0.1'><freejoint name='" + name +
         "_free'/><geom size='0.05'/></body>";
}

class FreeBaseTest : public urlab::testing::MujocoTest {
 protected:
  // The free base of the articulation `prefix` in a world made of `bodies`, by joint name ("" for
  // a fixed base), checked against the bindings' index too.
  std::string BaseOf(const std::string& bodies, const std::string& prefix) {
    ModelPtr m = CompileXmlString("<mujoco><worldbody>" + bodies + "</worldbody></mujoco>");
    DataPtr d = MakeData(m.get());
    const int joint = FreeBaseJoint(m.get(), prefix);
    ArticulationBindings b(m.get(), d.get(), prefix);
    const int index = FreeBaseIndex(b);
    if (joint < 0) {
      EXPECT_EQ(index, -1);
      return "";
    }
    EXPECT_GE(index, 0);
    if (index >= 0) {
      EXPECT_EQ(b.joints().all()[static_cast<std::size_t>(index)].id, joint);
    }
    return mj_id2name(m.get(), mjOBJ_JOINT, joint);
  }
};

TEST_F(FreeBaseTest, AFloatingRobotsRootJointIsItsBase) {
  EXPECT_EQ(BaseOf(Robot("a_torso", "<freejoint name='a_root'/>"), "a_"), "a_root");
}

TEST_F(FreeBaseTest, AFixedArmWithALooseBallInItsFileStaysFixed) {
  EXPECT_EQ(BaseOf(Robot("a_arm", "") + Ball("a_ball"), "a_"), "");
}

TEST_F(FreeBaseTest, ABallDeclaredBeforeTheRobotIsNotTheRobotsBase) {
  EXPECT_EQ(BaseOf(Ball("a_ball") + Robot("a_torso", "<freejoint name='a_root'/>"), "a_"),
            "a_root");
}

TEST_F(FreeBaseTest, AnotherArticulationsBodiesDoNotCount) {
  const std::string world =
      Robot("b_torso", "<freejoint name='b_root'/>") + Ball("a_ball") + Robot("a_arm", "");
  EXPECT_EQ(BaseOf(world, "a_"), "");
  EXPECT_EQ(BaseOf(world, "b_"), "b_root");
}

TEST_F(FreeBaseTest, AFreeObjectAloneIsItsOwnBase) {
  EXPECT_EQ(BaseOf(Ball("a_ball"), "a_"), "a_ball_free");
}

}  // namespace
}  // namespace urlab::physics
