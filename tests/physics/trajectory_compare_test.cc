// The comparison behind the round-trip tests must notice the smallest change.
#include "urlab/physics/trajectory_compare.h"

#include "mujoco_test.h"
#include "urlab/physics/model.h"

namespace urlab {
namespace {

std::string Pendulum(const std::string& length) {
  return "<mujoco><worldbody><body pos='0 0 1'><joint axis='0 1 0'/>"
         "<geom type='capsule' size='0.05' fromto='0 0 0 " +
         length +
         " 0 0'/></body>"
         "</worldbody></mujoco>";
}

class TrajectoryCompareTest : public testing::MujocoTest {};

TEST_F(TrajectoryCompareTest, IdenticalModelsCompareEqual) {
  auto a = physics::CompileXmlString(Pendulum("0.3"));
  auto b = physics::CompileXmlString(Pendulum("0.3"));
  EXPECT_EQ(physics::CompareSizes(a.get(), b.get()), "");
  EXPECT_EQ(physics::CompareTrajectories(a.get(), b.get(), 200), "");
}

TEST_F(TrajectoryCompareTest, OneUlpInTheModelIsADifferentTrajectory) {
  auto a = physics::CompileXmlString(Pendulum("0.3"));
  auto b = physics::CompileXmlString(Pendulum("0.30000000000000004"));  // next double
  EXPECT_EQ(physics::CompareSizes(a.get(), b.get()), "");
  EXPECT_NE(physics::CompareTrajectories(a.get(), b.get(), 200), "");
}

TEST_F(TrajectoryCompareTest, DifferentSizesAreNamed) {
  auto a = physics::CompileXmlString(Pendulum("0.3"));
  auto b = physics::CompileXmlString(
      "<mujoco><worldbody><body><joint/><geom size='1'/></body><geom size='1'/></worldbody>"
      "</mujoco>");
  EXPECT_EQ(physics::CompareSizes(a.get(), b.get()).rfind("ngeom", 0), 0u);
}

}  // namespace
}  // namespace urlab
