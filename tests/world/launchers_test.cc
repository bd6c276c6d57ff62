// Impulse launchers in scenes: the projectile pool is compiled in and lies still on its tray,
// FireLauncher gives the next projectile the launcher's speed along its +x at the muzzle (one
// command), it flies and lands away from the tray, the pool is reused round robin, a reset puts
// the projectiles back, and bad names are refused.
#include "urlab/world/launchers.h"

#include <gtest/gtest.h>

#include <cmath>

#include "mujoco_test.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

constexpr const char* kGround = R"(<mujoco model="ground">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="10 10 0.1"/>
  </worldbody>
</mujoco>)";

// Three launchers, one per shape: "ball" fires up at 30 degrees along +x.
constexpr const char* kLaunchers = R"(launchers:
  - name: ball
    pos: [0, 0, 0.5]
    euler: [0, -30, 0]
    speed: 5
    pool: 3
  - name: crate
    pos: [0, 2, 0.6]
    shape: box
    size: [0.04, 0.05, 0.03]
    mass: 1
    speed: 4
  - name: shell
    pos: [0, -2, 0.6]
    axisangle: [0, 0, 1, 90]
    shape: capsule
    size: [0.03, 0.06]
    pool: 2
)";

class LaunchersTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("launchers");
    testing::WriteTextFile(dir_, "ground.xml", kGround);
  }
  world::SceneConfig Scene(const std::string& launchers = kLaunchers,
                           const std::string& art = "ground") {
    return world::ParseScene(
        "articulations:\n  - name: " + art + "\n    mjcf: ground.xml\n" + launchers,
        dir_ + "/scene.yaml");
  }
  std::string dir_;
};

double Speed(const mjtNum* qvel) { return std::sqrt(mju_dot3(qvel, qvel)); }

TEST_F(LaunchersTest, PoolIsCompiledAndLiesStillOnItsTray) {
  const world::CompiledScene s = world::BuildScene(Scene());
  ASSERT_EQ(s.launchers.size(), 3u);
  const mjModel* m = s.model.get();
  EXPECT_EQ(s.launchers[0].bodies.size(), 3u);
  EXPECT_EQ(s.launchers[1].bodies.size(), 5u);  // the default pool
  EXPECT_EQ(s.launchers[2].bodies.size(), 2u);
  EXPECT_NEAR(m->body_mass[s.launchers[0].bodies[0]], 0.5, 1e-12);  // the default mass
  EXPECT_NEAR(m->body_mass[s.launchers[1].bodies[0]], 1.0, 1e-12);
  EXPECT_EQ(m->geom_type[m->body_geomadr[s.launchers[1].bodies[0]]], mjGEOM_BOX);
  EXPECT_EQ(m->geom_type[m->body_geomadr[s.launchers[2].bodies[0]]], mjGEOM_CAPSULE);
  EXPECT_GE(mj_name2id(m, mjOBJ_GEOM, "ball_tray"), 0);
  // The model's extent stays that of the scene: nothing parked far away.
  EXPECT_LT(m->stat.extent, 25);

  physics::DataPtr d = physics::MakeData(m);
  mj_forward(m, d.get());
  std::vector<std::array<double, 3>> start;
  for (const world::LauncherLayout& l : s.launchers) {
    for (int b : l.bodies) {
      start.push_back({d->xpos[3 * b], d->xpos[3 * b + 1], d->xpos[3 * b + 2]});
      EXPECT_LT(d->xpos[3 * b + 2], l.pos[2]) << "parked under the launcher";
      EXPECT_GT(d->xpos[3 * b + 2], 0.1) << "parked above the floor";
    }
  }
  for (int i = 0; i < 500; ++i) mj_step(m, d.get());  // 1 s
  std::size_t k = 0;
  for (const world::LauncherLayout& l : s.launchers) {
    for (std::size_t i = 0; i < l.bodies.size(); ++i, ++k) {
      const int b = l.bodies[i];
      EXPECT_LT(Speed(d->qvel + l.qvel_adr[i]), 1e-3) << l.name << " projectile " << i;
      EXPECT_LT(std::abs(d->xpos[3 * b + 2] - start[k][2]), 1e-3) << l.name << " " << i;
      EXPECT_LT(std::hypot(d->xpos[3 * b] - start[k][0], d->xpos[3 * b + 1] - start[k][1]), 1e-3)
          << l.name << " projectile " << i;
    }
  }
}

TEST_F(LaunchersTest, FireLaunchesAlongTheLauncherXAndTheProjectileLandsAway) {
  world::SessionOptions o;
  o.start_paused = true;
  o.as_fast_as_possible = true;
  auto session = world::Session::Create(Scene(), o);
  session->Start();
  const world::LauncherLayout& l = *session->FindLauncher("ball");
  EXPECT_NEAR(l.direction[0], std::sqrt(3) / 2, 1e-12);
  EXPECT_NEAR(l.direction[2], 0.5, 1e-12);
  const world::Session::Launch launch = session->FireLauncher("ball");
  EXPECT_EQ(launch.projectile, 0);
  ASSERT_TRUE(session->engine().WaitForCommand(launch.seq, std::chrono::seconds(5)).ok());
  const int b = l.bodies[0];
  session->engine().WithLockedData([&](const mjModel*, mjData* d) {
    const mjtNum* v = d->qvel + l.qvel_adr[0];
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(v[k], 5 * l.direction[k], 1e-9);
      EXPECT_EQ(v[3 + k], 0);
      EXPECT_NEAR(d->xpos[3 * b + k], l.muzzle[k], 1e-9);
    }
  });
  // 1.5 s later it has flown about 3 m along +x and lies on the floor, well past the tray.
  ASSERT_TRUE(session->engine()
                  .WaitForCommand(session->engine().Submit(physics::cmd::Step{750}),
                                  std::chrono::seconds(30))
                  .ok());
  session->engine().WithLockedData([&](const mjModel* m, mjData* d) {
    const int tray = mj_name2id(m, mjOBJ_GEOM, "ball_tray");
    EXPECT_GT(d->xpos[3 * b], 2.0);
    EXPECT_GT(d->xpos[3 * b], m->geom_pos[3 * tray] + 1.0);
    EXPECT_NEAR(d->xpos[3 * b + 1], 0, 0.02) << "stays in the launch plane";
    EXPECT_NEAR(d->xpos[3 * b + 2], 0.05, 0.01) << "on the floor";
    // The others still lie on the tray.
    EXPECT_LT(Speed(d->qvel + l.qvel_adr[1]), 1e-3);
  });
  session->Stop();
}

TEST_F(LaunchersTest, PoolIsReusedRoundRobinAndResetParksItAgain) {
  world::SessionOptions o;
  o.start_paused = true;
  auto session = world::Session::Create(Scene(), o);  // not started: commands apply at once
  const world::LauncherLayout& l = *session->FindLauncher("shell");
  ASSERT_EQ(l.bodies.size(), 2u);
  // The capsule flies along its axis: +y here (the launcher turned 90 degrees about z).
  EXPECT_NEAR(l.direction[1], 1, 1e-12);
  std::array<double, 3> parked{};
  session->engine().WithLockedData([&](const mjModel*, mjData* d) {
    for (int k = 0; k < 3; ++k) parked[k] = d->xpos[3 * l.bodies[0] + k];
    const mjtNum* axis = d->xmat + 9 * l.bodies[0];
    EXPECT_NEAR(std::abs(axis[2 * 3 + 2]), 0, 1e-9) << "a parked capsule lies on its side";
  });
  EXPECT_EQ(session->FireLauncher("shell").projectile, 0);
  EXPECT_EQ(session->FireLauncher(std::size_t{2}).projectile, 1);
  session->engine().WithLockedData([&](const mjModel* m, mjData* d) {
    // Move projectile 0 away, as if it had flown.
    d->qpos[l.qpos_adr[0]] = 3;
    mj_forward(m, d);
    const mjtNum* x = d->xmat + 9 * l.bodies[1];
    EXPECT_NEAR(x[1 * 3 + 2], 1, 1e-9) << "the capsule's axis points along the launch";
  });
  const world::Session::Launch third = session->FireLauncher("shell");
  EXPECT_EQ(third.projectile, 0) << "all out: the oldest is reused";
  session->engine().WithLockedData([&](const mjModel*, mjData* d) {
    EXPECT_NEAR(d->xpos[3 * l.bodies[0]], l.muzzle[0], 1e-9);
    EXPECT_NEAR(d->xpos[3 * l.bodies[0] + 1], l.muzzle[1], 1e-9);
    EXPECT_NEAR(d->qvel[l.qvel_adr[0] + 1], 5, 1e-9);  // the default speed
  });
  EXPECT_THROW(session->FireLauncher("cannon"), Error);
  EXPECT_THROW(session->FireLauncher(std::size_t{3}), Error);

  session->ResetToInitialState();
  session->engine().WithLockedData([&](const mjModel*, mjData* d) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(d->xpos[3 * l.bodies[0] + k], parked[k]);
    EXPECT_EQ(Speed(d->qvel + l.qvel_adr[0]), 0);
  });
}

TEST_F(LaunchersTest, LauncherNamedUnderAnArticulationsPrefixIsRefused) {
  const world::SceneConfig scene =
      Scene("launchers:\n  - name: robot_gun\n    pos: [0, 0, 1]\n", "robot");
  Diagnostics sink;
  world::CheckSceneConfig(scene, sink);
  ASSERT_TRUE(sink.has_errors());
  EXPECT_EQ(sink.all()[0].where.line, 5);
  EXPECT_NE(sink.all()[0].message.find("rename the launcher"), std::string::npos);
}

TEST_F(LaunchersTest, TrayUnderTheGroundIsRefusedWithTheHeightThatFits) {
  // A 5 cm ball parked 5 cm under the muzzle: at z = 0.1 its tray would be under the floor.
  const world::SceneConfig low = Scene("launchers:\n  - name: gun\n    pos: [0, 0, 0.1]\n");
  try {
    world::BuildScene(low);
    FAIL() << "compiled";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 5) << e.what();
    EXPECT_NE(e.message().find("under the ground plane 'ground_floor'"), std::string::npos)
        << e.message();
    // The height it names fits.
    const std::string m = e.message();
    const double fits = std::stod(m.substr(m.rfind(">= ") + 3));
    EXPECT_GT(fits, 0.1);
    EXPECT_NO_THROW(world::BuildScene(Scene("launchers:\n  - name: gun\n    pos: [0, 0, " +
                                            std::to_string(fits + 1e-3) + "]\n")));
  }
}

TEST_F(LaunchersTest, ExampleSceneFiresAtTheDog) {
  world::SessionOptions o;
  o.start_paused = true;
  o.as_fast_as_possible = true;
  auto session = world::Session::Create(
      world::LoadSceneFile(URLAB_SOURCE_DIR "/examples/scenes/go2_launcher.yaml"), o);
  session->Start();
  const world::LauncherLayout& l = *session->FindLauncher("cannon");
  const world::Session::Launch launch = session->FireLauncher("cannon");
  ASSERT_TRUE(session->engine().WaitForCommand(launch.seq, std::chrono::seconds(5)).ok());
  ASSERT_TRUE(session->engine()
                  .WaitForCommand(session->engine().Submit(physics::cmd::Step{100}),
                                  std::chrono::seconds(30))
                  .ok());
  session->engine().WithLockedData([&](const mjModel*, mjData* d) {
    EXPECT_GT(d->xpos[3 * l.bodies[0]], l.muzzle[0] + 1.0) << "0.2 s at 6 m/s toward the dog";
    EXPECT_LT(Speed(d->qvel + l.qvel_adr[1]), 1e-3) << "the rest of the pool lies still";
  });
  session->Stop();
}

}  // namespace
}  // namespace urlab
