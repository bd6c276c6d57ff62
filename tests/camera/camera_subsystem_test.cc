// The camera subsystem on a running scene (tests/data/cameras/rig.xml): frames of every stream
// arrive, a wait for a step gets a frame of that step or later, sockets bind ephemeral ports,
// and a camera the MJCF lacks is refused at its scene file line.
#include "urlab/camera/camera_subsystem.h"

#include <gtest/gtest.h>

#include <cstring>

#include "mujoco_test.h"
#include "urlab/world/manager.h"

namespace urlab::camera {
namespace {

class CameraSubsystemTest : public testing::MujocoTest {
 protected:
  world::SceneConfig Scene(const std::string& extra_yaml) {
    return world::ParseScene("articulations:\n  - name: rig\n    mjcf: " +
                                 testing::TestData("cameras/rig.xml") + "\n" + extra_yaml,
                             testing::TestData("cameras/inline.yaml"));
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
