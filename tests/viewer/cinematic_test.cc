// The keyframe camera path's interpolation (pure functions of the keys and the time).
#include "viewer/cinematic.h"

#include <gtest/gtest.h>

#include <cmath>

namespace urlab {
namespace {

using viewer::internal::CameraPose;
using viewer::internal::SamplePath;

std::vector<viewer::CameraKey> Keys() {
  return {{0, {0, 0, 1}, {1, 0, 0}},
          {1, {2, 0, 1}, {1, 1, 0}},
          {3, {2, 4, 2}, {0, 1, 0}},
          {4, {0, 4, 1}, {0, 0, 0}}};
}

double Dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

TEST(CinematicPath, PassesThroughEveryKeyAtItsTime) {
  for (const viewer::CameraKey& k : Keys()) {
    const CameraPose p = SamplePath(Keys(), k.time, false);
    EXPECT_LT(Dist(p.pos, k.pos), 1e-12) << "t=" << k.time;
    EXPECT_LT(Dist(p.look_at, k.look_at), 1e-12) << "t=" << k.time;
  }
}

TEST(CinematicPath, MovesSmoothly) {
  // Small time steps give small moves, and the velocity has no jump at the keys (C1): the
  // difference of consecutive displacements stays second order in the step.
  const double dt = 1e-3;
  double worst_step = 0, worst_kink = 0;
  CameraPose prev = SamplePath(Keys(), 0, false), prev2 = prev;
  for (double t = dt; t <= 4; t += dt) {
    const CameraPose p = SamplePath(Keys(), t, false);
    worst_step = std::max(worst_step, Dist(p.pos, prev.pos));
    if (t > 2 * dt) {
      for (std::size_t c = 0; c < 3; ++c) {
        worst_kink =
            std::max(worst_kink, std::abs((p.pos[c] - prev.pos[c]) - (prev.pos[c] - prev2.pos[c])));
      }
    }
    prev2 = prev;
    prev = p;
  }
  EXPECT_LT(worst_step, 20 * dt);
  EXPECT_LT(worst_kink, 100 * dt * dt);
}

TEST(CinematicPath, HoldsOrLoopsOutsideItsTimes) {
  EXPECT_LT(Dist(SamplePath(Keys(), -5, false).pos, Keys().front().pos), 1e-12);
  EXPECT_LT(Dist(SamplePath(Keys(), 99, false).pos, Keys().back().pos), 1e-12);
  // Looping: t and t + duration give the same pose.
  EXPECT_LT(Dist(SamplePath(Keys(), 5.5, true).pos, SamplePath(Keys(), 1.5, true).pos), 1e-12);
  // One key: that pose whatever the time.
  const std::vector<viewer::CameraKey> one = {Keys()[1]};
  EXPECT_LT(Dist(SamplePath(one, 7, true).look_at, one[0].look_at), 1e-12);
}

}  // namespace
}  // namespace urlab
