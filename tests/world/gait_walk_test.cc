// The gait controller walks the bundled quadruped and the Go2-style model of the example scenes
// at the twist its controller holds, through its actuators only: forward, turning, and standing
// again when released; the scene's twist modes are resolved as documented.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "support/mujoco_test.h"
#include "urlab/control/gait.h"
#include "urlab/core/error.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

struct Walk {
  double forward = 0;  // m along the starting heading
  double lateral = 0;  // m across it
  double yaw = 0;      // rad turned (unwrapped)
  double stand_height = 0, min_height = 1e9, max_height = 0;
  double min_upright = 1;  // smallest z component of the base's z axis
  double max_root_force = 0;
};

// Runs scene `path`: 0.5 s standing, then `seconds` at the twist (vx, vy, yaw rate) through the
// articulation's twist controller, as the viewer and set_twist drive it.
Walk RunWalk(const std::string& path, double vx, double vy, double wz, double seconds = 5) {
  auto session = world::Session::Create(world::LoadSceneFile(path), {});
  const world::Articulation& art = session->articulations().at(0);
  control::TwistController* twist = art.control->twist();
  EXPECT_NE(twist, nullptr);
  if (!twist) return {};
  physics::PhysicsEngine& engine = session->engine();
  Walk w;
  double x0 = 0, y0 = 0, yaw0 = 0, last_yaw = 0;
  const int root = twist->root_body();
  const auto base = [&](const mjData* d, double* x, double* y, double* z, double* yaw, double* up) {
    const mjtNum* r = d->xmat + 9 * root;
    *x = d->xpos[3 * root];
    *y = d->xpos[3 * root + 1];
    *z = d->xpos[3 * root + 2];
    *yaw = std::atan2(r[3], r[0]);
    *up = r[8];
  };
  const double dt = engine.model()->opt.timestep;
  engine.StepSync(static_cast<int>(0.5 / dt));
  engine.WithLockedData([&](const mjModel*, mjData* d) {
    double z, up;
    base(d, &x0, &y0, &z, &yaw0, &up);
    w.stand_height = z;
    last_yaw = yaw0;
  });
  twist->Attach(true);
  twist->SetTwist({vx, vy, wz});
  const int steps = static_cast<int>(seconds / dt);
  for (int i = 0; i < steps; ++i) {
    engine.StepSync(1);
    engine.WithLockedData([&](const mjModel*, mjData* d) {
      double x, y, z, yaw, up;
      base(d, &x, &y, &z, &yaw, &up);
      w.yaw += std::remainder(yaw - last_yaw, 2 * M_PI);
      last_yaw = yaw;
      w.min_height = std::min(w.min_height, z);
      w.max_height = std::max(w.max_height, z);
      w.min_upright = std::min(w.min_upright, up);
      for (int k = 0; k < 6; ++k) {
        w.max_root_force = std::max(w.max_root_force, std::abs(d->xfrc_applied[6 * root + k]));
      }
      const double dx = x - x0, dy = y - y0;
      w.forward = std::cos(yaw0) * dx + std::sin(yaw0) * dy;
      w.lateral = -std::sin(yaw0) * dx + std::cos(yaw0) * dy;
    });
  }
  return w;
}

std::string Example(const std::string& name) {
  return std::string(URLAB_SOURCE_DIR) + "/examples/scenes/" + name;
}

void Print(const std::string& what, const Walk& w) {
  std::printf(
      "%s: forward %.3f m, lateral %.3f m, yaw %.1f deg, base height %.3f..%.3f (standing "
      "%.3f), upright >= %.3f\n",
      what.c_str(), w.forward, w.lateral, w.yaw * 180 / M_PI, w.min_height, w.max_height,
      w.stand_height, w.min_upright);
}

// Standing: the base between 75 % and 125 % of its standing height and never tipped.
void ExpectStanding(const Walk& w) {
  EXPECT_GT(w.min_height, 0.75 * w.stand_height);
  EXPECT_LT(w.max_height, 1.25 * w.stand_height);
  EXPECT_GT(w.min_upright, 0.9) << "tilted by more than 25 degrees";
  EXPECT_EQ(w.max_root_force, 0) << "a gait acts only through the actuators";
}

class GaitWalkTest : public testing::MujocoTest,
                     public ::testing::WithParamInterface<const char*> {};

TEST_P(GaitWalkTest, WalksForwardAtHalfAMetrePerSecond) {
  const Walk w = RunWalk(Example(GetParam()), 0.5, 0, 0);
  Print(GetParam(), w);
  EXPECT_GT(w.forward, 1.0) << "5 s at 0.5 m/s";
  EXPECT_LT(std::abs(w.lateral), 0.5);
  EXPECT_LT(std::abs(w.yaw), 0.5);
  ExpectStanding(w);
}

TEST_P(GaitWalkTest, TurnsAtHalfARadianPerSecond) {
  const Walk w = RunWalk(Example(GetParam()), 0, 0, 0.5);
  Print(GetParam(), w);
  EXPECT_GT(w.yaw, 60 * M_PI / 180) << "5 s at 0.5 rad/s";
  EXPECT_LT(std::hypot(w.forward, w.lateral), 0.5) << "turning on the spot";
  ExpectStanding(w);
}

TEST_P(GaitWalkTest, WalksSidewaysAndTurnsWhileWalking) {
  Walk w = RunWalk(Example(GetParam()), 0, 0.3, 0);
  Print(std::string(GetParam()) + " sideways", w);
  EXPECT_GT(w.lateral, 0.5);
  ExpectStanding(w);
  w = RunWalk(Example(GetParam()), 0.5, 0, 0.5);
  Print(std::string(GetParam()) + " arc", w);
  EXPECT_GT(w.yaw, 60 * M_PI / 180);
  ExpectStanding(w);
}

class GaitSceneTest : public testing::MujocoTest {};

// The twist mode follows the controller unless the scene names it; contradictions and robots a
// gait cannot walk are refused at their file:line.
TEST_F(GaitSceneTest, TwistModesAndRefusals) {
  const std::string quadruped = std::string(URLAB_SOURCE_DIR) + "/examples/models/quadruped.xml";
  const std::string arm = std::string(URLAB_SOURCE_DIR) + "/examples/models/pendulum_arm.xml";
  const auto scene = [&](const std::string& mjcf, const std::string& extra) {
    return world::ParseScene(
        "articulations:\n  - name: dog\n    mjcf: " + mjcf + "\n" +
            (mjcf == arm ? "    keyframe: raised\n" : "    keyframe: stand\n") + extra,
        std::string(URLAB_SOURCE_DIR) + "/examples/scenes/x.yaml");
  };
  const auto mode = [&](const std::string& extra) {
    auto session = world::Session::Create(scene(quadruped, extra), {});
    return session->articulations().at(0).control->twist()->settings().mode;
  };
  EXPECT_EQ(mode("    controller: {type: gait}\n"), control::TwistMode::kGait);
  EXPECT_EQ(mode("    controller: {type: pd}\n"), control::TwistMode::kPolicy);
  EXPECT_EQ(mode("    controller: {type: pd}\n    twist: {mode: hover}\n"),
            control::TwistMode::kHover);
  const auto refused = [&](const std::string& mjcf, const std::string& extra, int line,
                           const std::string& message) {
    try {
      world::Session::Create(scene(mjcf, extra), {});
      ADD_FAILURE() << "accepted: " << extra;
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().line, line) << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  };
  refused(quadruped, "    controller: {type: gait}\n    twist: {mode: hover}\n", 2,
          "twist mode hover with a gait controller");
  refused(quadruped, "    controller: {type: pd}\n    twist: {mode: gait}\n", 2,
          "twist mode gait needs `controller: {type: gait}`");
  refused(arm, "    controller: {type: gait}\n", 5, "has no free joint");
}

INSTANTIATE_TEST_SUITE_P(Examples, GaitWalkTest,
                         ::testing::Values("quadruped_walk.yaml", "go2_network.yaml"));

}  // namespace
}  // namespace urlab
