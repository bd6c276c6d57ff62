// The Unreal convention: converting then rotating equals rotating then converting, for many
// rotations and vectors, and every conversion round-trips.
#include "urlab/client/unreal_coords.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace urlab::client {
namespace {

using V = std::array<double, 3>;
using Q = std::array<double, 4>;

// v' = q v q* (the same formula in both conventions).
V Rotate(const Q& q, const V& v) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const V t = {2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
  return {v[0] + w * t[0] + (y * t[2] - z * t[1]), v[1] + w * t[1] + (z * t[0] - x * t[2]),
          v[2] + w * t[2] + (x * t[1] - y * t[0])};
}

TEST(UnrealCoordsTest, PositionsFlipYAndScale) {
  EXPECT_EQ(MjToUePosition({1, 2, 3}), (V{100, -200, 300}));
  EXPECT_EQ(UeToMjPosition({100, -200, 300}), (V{1, 2, 3}));
  EXPECT_EQ(MjToUeQuat({0.5, 0.1, 0.2, 0.3}), (Q{0.5, -0.1, 0.2, -0.3}));
}

TEST(UnrealCoordsTest, RotationsCommuteWithTheConversion) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0, 1);
  for (int i = 0; i < 1000; ++i) {
    Q q = {n(rng), n(rng), n(rng), n(rng)};
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (double& c : q) c /= len;
    const V v = {n(rng), n(rng), n(rng)};
    const V mj_then_ue = MjToUePosition(Rotate(q, v));
    const V ue_rotated = Rotate(MjToUeQuat(q), MjToUePosition(v));
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(mj_then_ue[k], ue_rotated[k], 1e-9) << i;
    const Q back = UeToMjQuat(MjToUeQuat(q));
    for (int k = 0; k < 4; ++k) ASSERT_EQ(back[k], q[k]);
    const V pos = UeToMjPosition(MjToUePosition(v));
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(pos[k], v[k], 1e-15);
  }
}

}  // namespace
}  // namespace urlab::client
