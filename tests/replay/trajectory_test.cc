#include "urlab/replay/trajectory.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/files.h"
#include "urlab/physics/model.h"

namespace urlab::replay {
namespace {

using std::numbers::pi;

class TrajectoryTest : public urlab::testing::MujocoTest {
 protected:
  TrajectoryTest()
      : model_(physics::CompileXmlString(
            ReadInputFile(urlab::testing::TestData("replay/two_arms.xml"), "test model"))),
        tables_(ModelTables::Of(model_.get(), {"a", "b"})) {}

  const JointEntry& Joint(const char* name) const { return *tables_.FindJoint(name); }

  physics::ModelPtr model_;
  ModelTables tables_;
};

// The quaternion (w x y z) of a rotation by `angle` about z.
std::array<double, 4> AboutZ(double angle) {
  return {std::cos(angle / 2), 0, 0, std::sin(angle / 2)};
}

double Norm(const double* q) {
  return std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

// The angle of the rotation from a to b (0 .. pi), whatever the signs of a and b.
double AngleBetween(const double* a, const double* b) {
  const double dot = std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
  return 2 * std::acos(std::min(dot, 1.0));
}

TEST(SlerpTest, HalfwayBetweenZeroAndNinetyDegreesIsFortyFive) {
  const auto a = AboutZ(0), b = AboutZ(pi / 2), expected = AboutZ(pi / 4);
  double q[4];
  Slerp(a.data(), b.data(), 0.5, q);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q[i], expected[i], 1e-15) << i;
  Slerp(a.data(), b.data(), 0.25, q);
  const auto quarter = AboutZ(pi / 8);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q[i], quarter[i], 1e-15) << i;
  EXPECT_NEAR(Norm(q), 1, 1e-15);
}

TEST(SlerpTest, TakesTheShortArcWhenTheSignIsFlipped) {
  const auto a = AboutZ(0);
  auto b = AboutZ(pi / 2);
  for (double& v : b) v = -v;  // the same rotation
  double q[4];
  Slerp(a.data(), b.data(), 0.5, q);
  const auto expected = AboutZ(pi / 4);
  EXPECT_NEAR(AngleBetween(q, expected.data()), 0, 1e-7);
  EXPECT_NEAR(AngleBetween(q, a.data()), pi / 4, 1e-12);  // not 3/4 pi: the long way round
  EXPECT_GT(q[0], 0);                                     // a's hemisphere
  EXPECT_NEAR(Norm(q), 1, 1e-15);

  // Also from the other side: 170 and -170 degrees about z are 20 degrees apart.
  const auto c = AboutZ(170 * pi / 180), d = AboutZ(-170 * pi / 180);
  Slerp(c.data(), d.data(), 0.5, q);
  EXPECT_NEAR(AngleBetween(q, AboutZ(pi).data()), 0, 1e-7);
}

TEST(SlerpTest, EndpointsNearlyIdenticalAndUnitNorm) {
  const double a[4] = {0.5, 0.5, -0.5, 0.5};
  const double b[4] = {0.5, 0.5, -0.5, 0.5 + 1e-12};
  double q[4];
  for (const double s : {0.0, 0.3, 1.0}) {
    Slerp(a, b, s, q);
    EXPECT_NEAR(Norm(q), 1, 1e-15);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(q[i], a[i], 1e-12) << i;
  }
  const auto c = AboutZ(0.3), d = AboutZ(1.2);
  Slerp(c.data(), d.data(), 0, q);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q[i], c[i], 1e-15);
  Slerp(c.data(), d.data(), 1, q);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(q[i], d[i], 1e-15);

  // Random pairs and fractions: always unit-norm, and the angle splits as s says.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit;
  for (int n = 0; n < 1000; ++n) {
    double x[4], y[4];
    for (double& v : x) v = gauss(rng);
    for (double& v : y) v = gauss(rng);
    const double s = unit(rng);
    Slerp(x, y, s, q);
    EXPECT_NEAR(Norm(q), 1, 1e-14);
    double xn[4], yn[4];
    Slerp(x, x, 0, xn);
    Slerp(y, y, 0, yn);
    const double total = AngleBetween(xn, yn);
    EXPECT_NEAR(AngleBetween(xn, q), s * total, 1e-6);
    EXPECT_NEAR(AngleBetween(q, yn), (1 - s) * total, 1e-6);
  }
}

TEST(SlerpTest, ZeroQuaternionIsTheIdentity) {
  const double zero[4] = {0, 0, 0, 0};
  double q[4];
  Slerp(zero, zero, 0.5, q);
  EXPECT_EQ(q[0], 1);
  EXPECT_EQ(q[1], 0);
  EXPECT_EQ(q[2], 0);
  EXPECT_EQ(q[3], 0);
}

TEST_F(TrajectoryTest, SampleInterpolatesLinearPartsAndSlerpsQuaternions) {
  ASSERT_EQ(tables_.nq, 18);
  Trajectory traj;
  traj.nq = tables_.nq;
  traj.nv = tables_.nv;
  traj.time = {1, 3, 4};
  std::vector<double> row0(model_->qpos0, model_->qpos0 + model_->nq);
  std::vector<double> row1 = row0, row2 = row0;
  const JointEntry& root = Joint("a_root");
  const JointEntry& wrist = Joint("a_wrist");
  const JointEntry& slide = Joint("b_elbow");
  const JointEntry& hinge = Joint("a_elbow");
  const JointEntry& ball = Joint("b_ball");
  row0[root.qposadr + 0] = 1;
  row1[root.qposadr + 0] = 3;
  row1[root.qposadr + 2] = -2;
  row0[hinge.qposadr] = -1;
  row1[hinge.qposadr] = 1;
  row1[slide.qposadr] = 0.5;
  const auto z0 = AboutZ(0), z90 = AboutZ(pi / 2), z45 = AboutZ(pi / 4);
  std::copy(z0.begin(), z0.end(), row0.begin() + root.qposadr + 3);
  std::copy(z90.begin(), z90.end(), row1.begin() + root.qposadr + 3);
  std::copy(z0.begin(), z0.end(), row0.begin() + wrist.qposadr);
  for (int i = 0; i < 4; ++i) row1[wrist.qposadr + i] = -z90[i];  // sign flipped
  std::copy(z90.begin(), z90.end(), row0.begin() + ball.qposadr);
  std::copy(z0.begin(), z0.end(), row1.begin() + ball.qposadr);
  row2[hinge.qposadr] = 5;
  for (const auto* row : {&row0, &row1, &row2}) {
    traj.qpos.insert(traj.qpos.end(), row->begin(), row->end());
  }

  std::vector<double> q(18);
  traj.SampleQpos(tables_, 2, q.data());  // halfway between rows 0 and 1
  EXPECT_DOUBLE_EQ(q[root.qposadr + 0], 2);
  EXPECT_DOUBLE_EQ(q[root.qposadr + 1], 0);
  EXPECT_DOUBLE_EQ(q[root.qposadr + 2], -1);
  EXPECT_DOUBLE_EQ(q[hinge.qposadr], 0);
  EXPECT_DOUBLE_EQ(q[slide.qposadr], 0.25);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(q[root.qposadr + 3 + i], z45[i], 1e-15) << i;
    EXPECT_NEAR(q[ball.qposadr + i], z45[i], 1e-15) << i;
  }
  EXPECT_NEAR(AngleBetween(&q[wrist.qposadr], z45.data()), 0, 1e-7);  // not the long way
  EXPECT_NEAR(Norm(&q[wrist.qposadr]), 1, 1e-15);

  traj.SampleQpos(tables_, 3.5, q.data());  // between rows 1 and 2
  EXPECT_DOUBLE_EQ(q[hinge.qposadr], 3);

  // Clamped at the ends; a row's own time gives the row bit for bit.
  const std::vector<std::pair<double, const std::vector<double>*>> ends = {
      {-10.0, &row0}, {1.0, &row0}, {3.0, &row1}, {4.0, &row2}, {1e9, &row2}};
  for (const auto& [t, row] : ends) {
    traj.SampleQpos(tables_, t, q.data());
    EXPECT_EQ(q, *row) << "t=" << t;
  }
}

TEST_F(TrajectoryTest, SampleRefusesBadInput) {
  Trajectory traj;
  traj.nq = tables_.nq;
  traj.nv = tables_.nv;
  std::vector<double> q(18);
  EXPECT_THROW(traj.SampleQpos(tables_, 0, q.data()), Error);  // no rows
  traj.time = {0};
  traj.qpos.assign(18, 0.0);
  EXPECT_THROW(traj.SampleQpos(tables_, std::nan(""), q.data()), Error);
  traj.qpos.pop_back();
  EXPECT_THROW(traj.SampleQpos(tables_, 0, q.data()), Error);  // shape
}

TEST_F(TrajectoryTest, ChecksNameTheBadValue) {
  Trajectory traj;
  traj.nq = tables_.nq;
  traj.nv = tables_.nv;
  traj.time = {0, 1};
  traj.qpos.assign(36, 0.0);
  traj.qvel.assign(30, 0.0);
  EXPECT_NO_THROW(traj.Check(tables_));
  const auto message = [&](auto&& check) {
    try {
      check();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  traj.qpos[18 + 5] = std::nan("");
  EXPECT_EQ(message([&] { traj.CheckFinite(); }), "trajectory row 1 (time 1): qpos[5] is nan");
  traj.qpos[18 + 5] = 0;
  traj.qvel[2] = -INFINITY;
  EXPECT_EQ(message([&] { traj.CheckFinite(); }), "trajectory row 0 (time 0): qvel[2] is -inf");
  traj.qvel[2] = 0;
  traj.time[1] = INFINITY;
  EXPECT_EQ(message([&] { traj.CheckFinite(); }), "trajectory row 1: time is inf");
  traj.time[1] = 0;
  EXPECT_EQ(message([&] { traj.CheckTimes(); }), "trajectory row 1: time 0 is not after row 0's 0");
  traj.time[1] = 1;
  traj.qvel.pop_back();
  EXPECT_THROW(traj.CheckShape(tables_), Error);
  traj.qvel.clear();  // no velocities is fine
  EXPECT_NO_THROW(traj.Check(tables_));
  traj.nv = 3;
  EXPECT_THROW(traj.CheckShape(tables_), Error);
}

}  // namespace
}  // namespace urlab::replay
