// The gait controller's parts on the bundled quadruped (examples/models/quadruped.xml): legs found
// from the joint structure, their kinematics against MuJoCo's own, refusals of robots it cannot
// walk, and a trot that follows the twist through the actuators alone.
#include "urlab/control/gait.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "control/leg_kinematics.h"
#include "support/mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/physics/model.h"

namespace urlab::control {
namespace {

class GaitTest : public urlab::testing::MujocoTest {
 protected:
  void SetUp() override {
    m_ = physics::LoadXmlFile(std::string(URLAB_SOURCE_DIR) + "/examples/models/quadruped.xml");
    d_ = physics::MakeData(m_.get());
    key_ = mj_name2id(m_.get(), mjOBJ_KEY, "stand");
    ASSERT_GE(key_, 0);
    for (int i = 0; i < m_->nu; ++i) actuators_.push_back(i);
  }
  physics::ModelPtr m_;
  physics::DataPtr d_;
  int key_ = -1;
  std::vector<int> actuators_;
};

TEST_F(GaitTest, FindsFourLegsWhoseKinematicsAreMujocos) {
  PassthroughController probe;
  probe.Bind(m_.get(), actuators_);
  const int torso = mj_name2id(m_.get(), mjOBJ_BODY, "torso");
  const std::vector<legs::Leg> legs =
      legs::FindLegs(m_.get(), torso, probe.bindings(), m_->key_qpos + key_ * m_->nq);
  ASSERT_EQ(legs.size(), 4u);
  std::mt19937 rng(7);
  for (const legs::Leg& leg : legs) {
    ASSERT_EQ(leg.joints.size(), 3u) << leg.name;
    EXPECT_NEAR(leg.stand[2], -0.263, 0.002) << leg.name << ": the foot sphere's centre";
    // At random angles, the foot point is where mj_kinematics puts the foot geom.
    std::uniform_real_distribution<double> u(-0.4, 0.4);
    std::vector<double> q = leg.stand_q;
    for (double& v : q) v += u(rng);
    mju_copy(d_->qpos, m_->key_qpos + key_ * m_->nq, m_->nq);
    for (std::size_t k = 0; k < q.size(); ++k) d_->qpos[leg.joints[k].qpos_adr] = q[k];
    mj_kinematics(m_.get(), d_.get());
    const std::string geom = leg.name.substr(0, 2) + "_foot";
    const int g = mj_name2id(m_.get(), mjOBJ_GEOM, geom.c_str());
    ASSERT_GE(g, 0) << geom;
    mjtNum rel[3], want[3];
    mju_sub3(rel, d_->geom_xpos + 3 * g, d_->xpos + 3 * torso);
    mju_mulMatTVec(want, d_->xmat + 9 * torso, rel, 3, 3);
    double foot[3], jac[9];
    legs::FootPosition(leg, q, foot, jac);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(foot[i], want[i], 1e-9) << leg.name;
    // The Jacobian agrees with a finite difference, and IK finds the angles back.
    for (std::size_t k = 0; k < 3; ++k) {
      std::vector<double> q2 = q;
      q2[k] += 1e-6;
      double f2[3];
      legs::FootPosition(leg, q2, f2, nullptr);
      for (std::size_t i = 0; i < 3; ++i) {
        EXPECT_NEAR((f2[i] - foot[i]) / 1e-6, jac[i * 3 + k], 1e-4);
      }
    }
    std::vector<double> solved = leg.stand_q;
    EXPECT_LT(legs::SolveIk(leg, foot, solved), 1e-5) << leg.name << ": within 10 um";
  }
}

TEST_F(GaitTest, RefusesRobotsItCannotWalk) {
  // A fixed-base arm: no free joint.
  physics::ModelPtr arm =
      physics::LoadXmlFile(std::string(URLAB_SOURCE_DIR) + "/examples/models/servo_arm.xml");
  GaitController on_arm({}, {});
  std::vector<int> ids;
  for (int i = 0; i < arm->nu; ++i) ids.push_back(i);
  try {
    on_arm.Bind(arm.get(), ids);
    ADD_FAILURE() << "an arm was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("free joint"), std::string::npos) << e.what();
  }
  // Three legs of the quadruped (its rear-right leg's actuators left out).
  GaitController three({.stand_key = key_}, {});
  try {
    three.Bind(m_.get(), std::vector<int>(actuators_.begin(), actuators_.end() - 3));
    ADD_FAILURE() << "three legs were accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("four legs"), std::string::npos) << e.what();
  }
  // A leg with only two actuated hinges.
  std::vector<int> two(actuators_.begin() + 1, actuators_.end());
  try {
    three.Bind(m_.get(), two);
    ADD_FAILURE() << "a two-hinge leg was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("FL_shin"), std::string::npos) << e.what();
  }
}

TEST_F(GaitTest, TrotsAtTheTwistThroughTheActuatorsAlone) {
  GaitController gait({.stand_key = key_}, {});
  gait.Bind(m_.get(), actuators_);
  EXPECT_EQ(gait.num_legs(), 4);
  EXPECT_NEAR(gait.stance_height(), 0.263, 0.002);
  TwistController twist({.mode = TwistMode::kGait, .max_vx = 1.0});
  twist.Bind(m_.get(), mj_name2id(m_.get(), mjOBJ_JOINT, "root"));
  gait.SetTwistSource(&twist);
  mj_resetDataKeyframe(m_.get(), d_.get(), key_);
  mj_forward(m_.get(), d_.get());
  // The source's targets: the standing pose (what a detached gait holds).
  std::vector<double> stand(m_->key_ctrl + key_ * m_->nu, m_->key_ctrl + (key_ + 1) * m_->nu);
  const auto run = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(seconds / m_->opt.timestep); ++i) {
      twist.Apply(m_.get(), d_.get());
      gait.ComputeAndApply(m_.get(), d_.get(), stand);
      mj_step(m_.get(), d_.get());
    }
  };
  run(0.5);
  EXPECT_FALSE(gait.walking());
  const double x0 = d_->qpos[0], z0 = d_->qpos[2];
  twist.Attach(true);
  twist.SetTwist({0.5, 0, 0});
  run(4);
  EXPECT_TRUE(gait.walking());
  EXPECT_GT(d_->qpos[0] - x0, 0.8) << "4 s at 0.5 m/s";
  EXPECT_GT(d_->qpos[2], 0.75 * z0);
  for (int i = 0; i < 6 * m_->nbody; ++i) ASSERT_EQ(d_->xfrc_applied[i], 0);
  // Released: it stops walking and stands on the source's targets.
  twist.Attach(false);
  run(1.5);
  EXPECT_FALSE(gait.walking());
  EXPECT_LT(std::hypot(d_->qvel[0], d_->qvel[1]), 0.05);
  EXPECT_GT(d_->qpos[2], 0.75 * z0);
}

}  // namespace
}  // namespace urlab::control
