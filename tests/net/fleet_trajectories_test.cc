// FleetContext's batch-matched bare loops (src/net/fleet_trajectories.cc): the actions a batched
// figure steps with, and the bare loop that times the same trajectories.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <atomic>

#include "net/fleet_context.h"
#include "urlab/physics/model.h"

namespace urlab::net {
namespace {

// One limited and one unlimited motor on a pendulum resting on a floor.
constexpr const char* kTrajectoryArmXml = R"(
<mujoco>
  <worldbody>
    <geom type="plane" size="2 2 0.1"/>
    <body pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body pos="0.5 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="hinge" ctrllimited="true" ctrlrange="-0.25 0.5"/>
    <motor joint="elbow" ctrllimited="false"/>
  </actuator>
</mujoco>)";

class FleetTrajectoriesTest : public ::testing::Test {
 protected:
  FleetTrajectoriesTest()
      : model_(physics::CompileXmlString(kTrajectoryArmXml)),
        data_(physics::MakeData(model_.get())),
        ctx_(options_, "", "arm", model_.get(), data_.get()) {}

  FleetBenchOptions options_;
  physics::ModelPtr model_;
  physics::DataPtr data_;
  FleetContext ctx_;
};

TEST_F(FleetTrajectoriesTest, ActionsStayInEachActuatorsRangeAndFollowTheSeed) {
  const FleetContext::Trajectories t = ctx_.MakeTrajectories(5, 3, 2, 10, 7);
  ASSERT_EQ(t.actions.size(), 3u * 5u * 2u);
  EXPECT_EQ(t.nu, 2);
  bool spread = false;
  for (std::size_t k = 0; k < t.actions.size(); k += 2) {
    EXPECT_GE(t.actions[k], -0.25);
    EXPECT_LE(t.actions[k], 0.5);
    EXPECT_GE(t.actions[k + 1], -1.0);  // unlimited: [-1, 1]
    EXPECT_LE(t.actions[k + 1], 1.0);
    spread |= t.actions[k] != t.actions[0];
  }
  EXPECT_TRUE(spread);
  EXPECT_EQ(ctx_.MakeTrajectories(5, 3, 2, 10, 7).actions, t.actions);
  EXPECT_NE(ctx_.MakeTrajectories(5, 3, 2, 10, 8).actions, t.actions);
  EXPECT_THROW(ctx_.MakeTrajectories(0, 3, 2, 10, 7), std::exception);
  EXPECT_THROW(ctx_.MakeTrajectories(5, 3, 2, 10, 7, 0), std::exception);  // hold < 1
  EXPECT_EQ(ctx_.MakeTrajectories(5, 3, 2, 10, 7, 4).hold, 4);
}

TEST_F(FleetTrajectoriesTest, EveryEnvironmentStartsFromTheResetStateOnOneThreadOrTwo) {
  const FleetContext::Trajectories t = ctx_.MakeTrajectories(5, 3, 2, 20, 1);
  for (const bool in_turn : {false, true}) {
    for (const int threads : {1, 2, 9}) {
      std::atomic<int> resets{0};
      ctx_.reset_state = [&](const mjModel* m, mjData* d) {
        mj_resetData(m, d);
        d->qpos[0] = 0.3;
        ++resets;
      };
      EXPECT_GT(ctx_.TrajectoryRate(t, threads, in_turn), 0.0) << threads << " " << in_turn;
      EXPECT_EQ(resets.load(), 5) << threads << " " << in_turn;
    }
  }
}

}  // namespace
}  // namespace urlab::net
