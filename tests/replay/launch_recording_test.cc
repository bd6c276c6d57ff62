// Launches are state commands like any other: a run with a launcher firing while it records
// re-simulates bit for bit, each launch marked as a set_state jump.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "support/mujoco_test.h"
#include "support/wait.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"
#include "urlab/world/session.h"

namespace urlab::replay {
namespace {

using namespace std::chrono_literals;

class LaunchRecordingTest : public urlab::testing::MujocoTest {
 protected:
  std::string dir_ = urlab::testing::MakeTempDir("launch_recording");
};

TEST_F(LaunchRecordingTest, LaunchesReSimulateBitForBit) {
  // The bundled arm (its floor catches the projectiles) beside a launcher.
  const world::SceneConfig scene = world::ParseScene(
      "articulations:\n  - name: arm\n    mjcf: " URLAB_SOURCE_DIR
      "/examples/models/pendulum_arm.xml\n"
      "launchers:\n  - {name: gun, pos: [-1.5, 1, 0.4], euler: [0, -20, 0], pool: 2, speed: 3}\n",
      dir_ + "/scene.yaml");
  world::SessionOptions o;
  o.as_fast_as_possible = true;
  auto session = world::Session::Create(scene, o);
  physics::PhysicsEngine& engine = session->engine();
  // A deep ring: a starved writer must not drop frames (a gap ends bit-exact re-simulation).
  Recorder recorder(engine, {{"arm"}, "<mujoco/>", scene.path}, 1 << 17);
  session->Start();
  RecorderOptions ro;
  ro.path = dir_ + "/launch.urrec";
  recorder.Start(ro);
  const auto steps = [&](std::uint64_t n) {
    const std::uint64_t from = engine.step_count();
    ASSERT_TRUE(urlab::testing::WaitFor([&] { return engine.step_count() >= from + n; }, 60000ms));
  };
  steps(100);
  for (int i = 0; i < 3; ++i) {  // the third reuses the first projectile in flight
    const world::Session::Launch l = session->FireLauncher("gun");
    EXPECT_EQ(l.projectile, i % 2);
    ASSERT_TRUE(engine.WaitForCommand(l.seq, 10s).ok());
    steps(150);
  }
  const RecorderStatus st = recorder.Stop();
  session->Stop();
  EXPECT_EQ(st.dropped, 0u);
  EXPECT_GE(st.markers, 3u);

  const RecordingReader reader = RecordingReader::Open(ro.path);
  int launches = 0;
  for (const Record& r : ReadAllRecords(reader)) {
    if (const auto* mk = std::get_if<Marker>(&r)) {
      launches += (mk->flags & physics::kDiscontinuitySetState) != 0;
    }
  }
  EXPECT_EQ(launches, 3);
  const ResimReport report = Resimulate(reader);
  EXPECT_TRUE(report.identical) << report.str();
  EXPECT_GE(report.steps_checked, 500u);
}

}  // namespace
}  // namespace urlab::replay
