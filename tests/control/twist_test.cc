// The twist controller drives a free base to the commanded planar velocity (in its heading frame)
// and yaw rate through the root body's applied force, clamps commands to its maxima, and gives
// the body back when detached.
#include "urlab/control/twist.h"

#include <gtest/gtest.h>

#include <cmath>

#include "support/mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab::control {
namespace {

// A box floating without gravity, turned 90 degrees about z (its heading is the world's +y), with
// a child body so the controller's inertia sums a subtree; a hinge elsewhere.
constexpr const char* kXml = R"(<mujoco>
  <option gravity="0 0 0" timestep="0.002"/>
  <worldbody>
    <body name="base" pos="0 0 1" euler="0 0 90">
      <freejoint name="root"/>
      <geom type="box" size="0.3 0.2 0.1" mass="5"/>
      <body name="head" pos="0.3 0 0.1">
        <geom type="sphere" size="0.08" mass="1"/>
      </body>
    </body>
    <body name="door" pos="3 0 1">
      <joint name="hinge" type="hinge" axis="0 0 1"/>
      <geom type="box" size="0.1 0.1 0.1"/>
    </body>
  </worldbody>
</mujoco>)";

class TwistTest : public urlab::testing::MujocoTest {};

TEST_F(TwistTest, ReachesTheCommandedTwistInTheHeadingFrame) {
  physics::ModelPtr m = physics::CompileXmlString(kXml);
  physics::DataPtr d = physics::MakeData(m.get());
  mj_forward(m.get(), d.get());
  TwistController twist(
      {.mode = TwistMode::kHover, .max_vx = 1.0, .max_vy = 0.5, .max_yaw_rate = 0.5});
  twist.Bind(m.get(), mj_name2id(m.get(), mjOBJ_JOINT, "root"));
  EXPECT_EQ(twist.root_body(), mj_name2id(m.get(), mjOBJ_BODY, "base"));
  EXPECT_THROW(twist.Bind(m.get(), mj_name2id(m.get(), mjOBJ_JOINT, "hinge")), Error);
  twist.Bind(m.get(), mj_name2id(m.get(), mjOBJ_JOINT, "root"));

  // Clamped to the maxima; non-finite components become zero.
  EXPECT_EQ(twist.SetTwist({5, -5, NAN}), (Twist{1.0, -0.5, 0}));
  twist.SetActions(0xffff);
  EXPECT_EQ(twist.actions(), 0x3ffu) << "ten action bits";

  // Detached: nothing is applied.
  twist.Apply(m.get(), d.get());
  for (int i = 0; i < 6; ++i) EXPECT_EQ(d->xfrc_applied[6 * twist.root_body() + i], 0);

  twist.Attach(true);
  EXPECT_EQ(twist.twist(), Twist{}) << "attaching starts from rest";
  EXPECT_EQ(twist.actions(), 0u);
  twist.SetTwist({0.6, 0, 0});      // forward: the box faces +y (before it turns)
  for (int i = 0; i < 1000; ++i) {  // 2 s, gains 4/s: the error decays by e^-8
    twist.Apply(m.get(), d.get());
    mj_step(m.get(), d.get());
  }
  const mjtNum* v = d->qvel;  // free joint: world linear velocity
  EXPECT_NEAR(v[0], 0, 0.01);
  EXPECT_NEAR(v[1], 0.6, 0.01);
  EXPECT_NEAR(v[2], 0, 1e-9) << "no vertical force";

  // Turning: the yaw rate follows, and the heading (and so the velocity's direction) turns.
  twist.SetTwist({0.6, 0, 0.5});
  for (int i = 0; i < 1000; ++i) {
    twist.Apply(m.get(), d.get());
    mj_step(m.get(), d.get());
  }
  const mjtNum* r = d->xmat + 9 * twist.root_body();
  const mjtNum wz = r[6] * d->qvel[3] + r[7] * d->qvel[4] + r[8] * d->qvel[5];
  EXPECT_NEAR(wz, 0.5, 0.02);
  const double heading = std::atan2(r[3], r[0]);
  EXPECT_GT(std::remainder(heading - M_PI / 2, 2 * M_PI), 0.7) << "turned left by ~0.9 rad";
  // The velocity turned with the heading (forward stays forward), at the commanded speed.
  EXPECT_NEAR(std::hypot(d->qvel[0], d->qvel[1]), 0.6, 0.05);
  const double lag = std::remainder(heading - std::atan2(d->qvel[1], d->qvel[0]), 2 * M_PI);
  EXPECT_LT(std::abs(lag), 0.2);

  // Detaching gives the row back (zero) once.
  twist.Attach(false);
  twist.Apply(m.get(), d.get());
  for (int i = 0; i < 6; ++i) EXPECT_EQ(d->xfrc_applied[6 * twist.root_body() + i], 0);
  d->xfrc_applied[6 * twist.root_body()] = 3;  // someone else's force stays
  twist.Apply(m.get(), d.get());
  EXPECT_EQ(d->xfrc_applied[6 * twist.root_body()], 3);
}

// Outside hover mode the controller only holds the twist: nothing touches the root body (a gait
// controller or a walking policy reads it).
TEST_F(TwistTest, OnlyHoverModePushesTheRootBody) {
  EXPECT_EQ(TwistSettings{}.mode, TwistMode::kPolicy) << "hover is chosen explicitly";
  EXPECT_EQ(ParseTwistMode("hover"), TwistMode::kHover);
  EXPECT_EQ(ParseTwistMode("gait"), TwistMode::kGait);
  EXPECT_EQ(ParseTwistMode("policy"), TwistMode::kPolicy);
  EXPECT_EQ(ParseTwistMode("walk"), std::nullopt);
  physics::ModelPtr m = physics::CompileXmlString(kXml);
  physics::DataPtr d = physics::MakeData(m.get());
  mj_forward(m.get(), d.get());
  for (TwistMode mode : {TwistMode::kPolicy, TwistMode::kGait}) {
    TwistController twist({.mode = mode});
    twist.Bind(m.get(), mj_name2id(m.get(), mjOBJ_JOINT, "root"));
    twist.Attach(true);
    EXPECT_EQ(twist.SetTwist({5, 0, 0.2}), (Twist{1.0, 0, 0.2})) << "still clamped";
    for (int i = 0; i < 100; ++i) {
      twist.Apply(m.get(), d.get());
      mj_step(m.get(), d.get());
    }
    for (int i = 0; i < 6; ++i) EXPECT_EQ(d->xfrc_applied[6 * twist.root_body() + i], 0);
    EXPECT_EQ(d->qvel[0], 0) << ToString(mode) << " mode moved the base";
  }
}

}  // namespace
}  // namespace urlab::control
