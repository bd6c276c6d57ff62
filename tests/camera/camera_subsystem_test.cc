// The camera subsystem on a running scene (tests/data/cameras/rig.xml): frames of every stream
// arrive, a wait for a step gets a frame of that step or later, sockets bind ephemeral ports,
// and a camera the MJCF lacks is refused at its scene file line.
#include "urlab/camera/camera_subsystem.h"

#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <vector>

#include "mujoco_test.h"
#include "urlab/camera/scene_settings.h"
#include "urlab/core/error.h"
#include "urlab/world/manager.h"

namespace urlab::camera {
namespace {

class CameraSubsystemTest : public testing::MujocoTest {
 protected:
  void SetUp() override { RegisterSceneSections(); }  // the scenes here have `cameras:`
  world::SceneConfig Scene(const std::string& extra_yaml) {
    return world::ParseScene("articulations:\n  - name: rig\n    mjcf: " +
                                 testing::TestData("cameras/rig.xml") + "\n" + extra_yaml,
                             testing::TestData("cameras/inline.yaml"));
  }
  // Lockstep tests start paused: the step count is theirs from the first step.
  static world::ManagerOptions Paused() {
    world::ManagerOptions o;
    o.start_paused = true;
    return o;
  }
  static CameraOptions Options(const world::SceneConfig& s) {
    CameraOptions o = CameraOptionsFromScene(s);
    o.base_port = 0;
    o.bind_host = "127.0.0.1";
    return o;
  }
};

TEST_F(CameraSubsystemTest, StreamsRenderAndWaitsGetTheirStep) {
  const world::SceneConfig s = Scene(
      "    cameras: [wrist]\ncameras:\n  width: 32\n  height: 24\n  rate: 20\n"
      "  streams:\n    rig/top: {modes: [depth, instance]}\n");
  world::Manager manager;
  auto& cams = static_cast<CameraSubsystem&>(
      manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s))));
  manager.BeginPlay(s);
  ASSERT_EQ(cams.Streams().size(), 3u);
  EXPECT_FALSE(cams.backend().empty());
  const int depth = cams.Find("rig", "top/depth");
  const int instance = cams.Find("rig", "top/instance");
  const int wrist = cams.Find("rig", "wrist");
  ASSERT_GE(depth, 0);
  ASSERT_GE(instance, 0);
  ASSERT_GE(wrist, 0);
  EXPECT_EQ(cams.Streams()[depth].topic, "rig/camera/top/depth ");
  EXPECT_EQ(cams.Streams()[instance].id_names, std::vector<std::string>{"rig"});
  for (const auto& info : cams.Streams()) {
    EXPECT_EQ(info.endpoint.rfind("tcp://127.0.0.1:", 0), 0u) << info.endpoint;
  }
  // A frame showing a step at least 50 steps ahead of now: rendered for the wait.
  const std::uint64_t target = manager.session().engine().step_count() + 50;
  world::CameraFrame f;
  ASSERT_TRUE(cams.WaitForStep(depth, target, std::chrono::seconds(10), f));
  EXPECT_GE(f.step, target);
  ASSERT_EQ(f.bytes->size(), 32u * 24u * sizeof(float));
  float centre = 0;
  std::memcpy(&centre, f.bytes->data() + (12 * 32 + 16) * sizeof(float), sizeof(float));
  EXPECT_NEAR(centre, 1.9, 1e-3);
  ASSERT_TRUE(cams.WaitForStep(instance, target, std::chrono::seconds(10), f));
  // The box belongs to the articulation: instance id 0 (B = 1, G = R = 0).
  const std::uint8_t* px = f.bytes->data() + 4 * (12 * 32 + 16);
  EXPECT_EQ(px[0], 1);
  EXPECT_EQ(px[1] | px[2], 0);
  ASSERT_TRUE(cams.Latest(wrist, f));
  EXPECT_EQ(f.bytes->size(), 32u * 24u * 4u);
  manager.EndPlay();
  EXPECT_GT(cams.counters().renders, 0u);
}

// Lockstep with a sync wait at every step, from the step a setting was given: the step of the
// frame each wait returns, -1 while it is none or one from before the setting (a new setting
// drops the frames held; the camera goes on showing its last frame until the first release).
std::vector<std::int64_t> DelayedFrameSteps(world::Manager& manager, CameraSubsystem& cams,
                                            int stream, int steps) {
  physics::PhysicsEngine& engine = manager.session().engine();
  const std::uint64_t start = engine.step_count();
  std::vector<std::int64_t> out;
  for (int i = 0; i < steps; ++i) {
    engine.StepSync(1);
    world::CameraFrame f;
    const bool got = cams.WaitForStep(stream, engine.step_count(), std::chrono::seconds(10), f);
    out.push_back(got && f.step > start ? static_cast<std::int64_t>(f.step) : -1);
  }
  return out;
}

TEST_F(CameraSubsystemTest, ADelayedCameraShowsTheStateItsDelayAgo) {
  const world::SceneConfig s = Scene("    cameras: [wrist]\ncameras: {width: 16, height: 12}\n");
  world::Manager manager(Paused());
  auto& cams = static_cast<CameraSubsystem&>(
      manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s))));
  manager.BeginPlay(s);
  const int wrist = cams.Find("rig", "wrist");
  ASSERT_GE(wrist, 0);
  physics::LatencySetting three;
  three.delay = 3;
  cams.SetDelay("rig/wrist", three, 1);
  EXPECT_EQ(cams.Delay("rig/wrist"), three);
  const std::uint64_t start = manager.session().engine().step_count();
  const auto steps = DelayedFrameSteps(manager, cams, wrist, 12);
  // Nothing is released for the first three steps; from then on each frame is 3 steps old.
  for (int i = 0; i < 12; ++i) {
    const auto now = static_cast<std::int64_t>(start) + i + 1;
    if (i < 3) {
      EXPECT_EQ(steps[i], -1) << i;
    } else {
      EXPECT_EQ(steps[i], now - 3) << i;
    }
  }
  // A rate cap of 1/(4 dt): the frame shown changes at most every 4 steps.
  physics::LatencySetting capped;
  capped.delay = 1;
  capped.rate_hz = 1.0 / (4 * manager.session().engine().timestep());
  cams.SetDelay("rig/wrist", capped, 1);
  const auto c = DelayedFrameSteps(manager, cams, wrist, 24);
  int changes = 0;
  for (std::size_t i = 1; i < c.size(); ++i) changes += c[i] != c[i - 1];
  EXPECT_GE(changes, 4);
  EXPECT_LE(changes, 7);
  EXPECT_THROW(cams.SetDelay("rig/nope", three, 1), Error);
  manager.EndPlay();
}

TEST_F(CameraSubsystemTest, JitteredDelaysStayInRangeKeepOrderAndFollowTheSeed) {
  const world::SceneConfig s = Scene("    cameras: [wrist]\ncameras: {width: 16, height: 12}\n");
  physics::LatencySetting jittery;
  jittery.delay = 3;
  jittery.jitter = 2;
  // Two runs from the start with the same seed, one with another.
  auto run = [&](std::uint64_t seed) {
    world::Manager manager(Paused());
    auto& cams = static_cast<CameraSubsystem&>(
        manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s))));
    manager.BeginPlay(s);
    cams.SetDelay("rig/wrist", jittery, seed);
    const auto start = static_cast<std::int64_t>(manager.session().engine().step_count());
    auto steps = DelayedFrameSteps(manager, cams, cams.Find("rig", "wrist"), 40);
    manager.EndPlay();
    for (auto& v : steps) v = v < 0 ? -1 : v - start;
    return steps;
  };
  const auto a = run(7), b = run(7), c = run(8);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  std::set<std::int64_t> delays;
  EXPECT_EQ(a[0], -1);
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] < 0) continue;
    const auto now = static_cast<std::int64_t>(i + 1);
    EXPECT_GE(now - a[i], 1) << i;
    EXPECT_LE(now - a[i], 5) << i;
    if (i > 0 && a[i - 1] >= 0) {
      EXPECT_GE(a[i], a[i - 1]) << i;
    }
    delays.insert(now - a[i]);
  }
  EXPECT_GE(delays.size(), 3u) << "the jitter varies the delay";
}

TEST_F(CameraSubsystemTest, TheScenesCameraLatencyDelaysFromTheFirstFrame) {
  const world::SceneConfig s = Scene(
      "    cameras: [wrist]\ncameras:\n  width: 16\n  height: 12\n  streams:\n"
      "    rig/wrist: {latency: {delay_steps: 2}}\n");
  world::Manager manager(Paused());
  auto& cams = static_cast<CameraSubsystem&>(
      manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s))));
  manager.BeginPlay(s);
  physics::LatencySetting two;
  two.delay = 2;
  EXPECT_EQ(cams.Delay("rig/wrist"), two);
  const auto start = static_cast<std::int64_t>(manager.session().engine().step_count());
  const auto steps = DelayedFrameSteps(manager, cams, cams.Find("rig", "wrist"), 8);
  for (std::size_t i = 2; i < steps.size(); ++i) {
    EXPECT_EQ(steps[i], start + static_cast<std::int64_t>(i) + 1 - 2) << i;
  }
  manager.EndPlay();
  // A bad setting is refused at its line.
  try {
    Scene(
        "    cameras: [wrist]\ncameras:\n  streams:\n    rig/wrist: {latency: {delay_steps: "
        "-1}}\n");
    ADD_FAILURE() << "a negative camera delay was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cameras.streams.rig/wrist.latency"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("inline.yaml:7"), std::string::npos) << e.what();
  }
}

TEST_F(CameraSubsystemTest, AnUnknownCameraIsRefusedAtItsLine) {
  const world::SceneConfig s = Scene("cameras:\n  streams:\n    rig/nose: {rate: 5}\n");
  world::Manager manager;
  manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s)));
  try {
    manager.BeginPlay(s);
    FAIL() << "accepted a camera the MJCF lacks";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 6) << e.what();
    EXPECT_NE(std::string(e.what()).find("no camera 'nose'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("top, wrist"), std::string::npos) << e.what();
  }
}

TEST_F(CameraSubsystemTest, TheToggleTurnsEveryCameraOff) {
  const world::SceneConfig s = Scene("    cameras: true\ncameras: {enabled: false}\n");
  world::Manager manager;
  auto& cams = static_cast<CameraSubsystem&>(
      manager.AddSubsystem(std::make_unique<CameraSubsystem>(Options(s))));
  manager.BeginPlay(s);
  EXPECT_TRUE(cams.Streams().empty());
  EXPECT_TRUE(cams.backend().empty());
}

}  // namespace
}  // namespace urlab::camera
