// The cameras' scene section (urlab/camera/scene_settings.h): registered with the scene parser,
// `cameras:` is parsed by the camera module into its own settings; bad input is an InputError at
// its file:line as when world/scene_file parsed it, and the streams' cameras are checked against
// the compiled scene through the registration, so `validate` (world::Validate) and begin-play
// (world::BuildCheckedScene) refuse the same scene.
#include "urlab/camera/scene_settings.h"

#include <gtest/gtest.h>

#include <string>

#include "mujoco_test.h"
#include "scene_errors.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_checks.h"
#include "urlab/world/scene_file.h"

namespace urlab {
namespace {

using testing::WithArm;

class CameraSceneSections : public testing::MujocoTest {
 protected:
  void SetUp() override {
    camera::RegisterSceneSections();
    dir_ = testing::MakeTempDir("camera_sections");
  }
  std::string dir_;
};

TEST_F(CameraSceneSections, BadInputIsRefusedAtItsLine) {
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      {WithArm("cameras: []\n"), 4, "cameras must be a mapping"},
      {WithArm("cameras: {modes: [rgb, infrared]}\n"), 4, "unknown mode 'infrared'"},
      {WithArm("cameras: {modes: [rgb, rgb]}\n"), 4, "listed twice"},
      {WithArm("cameras: {modes: []}\n"), 4, "cameras.modes must name at least one mode"},
      {WithArm("cameras: {width: 0}\n"), 4, "cameras.width must be 1 to 8192"},
      {WithArm("cameras: {rate: 0}\n"), 4, "cameras.rate must be > 0"},
      {WithArm("cameras: {gl: glx}\n"), 4, "cameras.gl must be auto, egl or osmesa"},
      {WithArm("cameras: {shadows: maybe}\n"), 4, "cameras.shadows must be true or false"},
      {WithArm("cameras: {fps: 30}\n"), 4, "unknown key 'fps' in cameras"},
      {WithArm("cameras:\n  streams:\n    ghost/head: {rate: 5}\n"), 6, "no articulation 'ghost'"},
      {WithArm("cameras:\n  streams:\n    head: {rate: 5}\n"), 6, "\"articulation/camera\""},
      {WithArm("cameras:\n  streams:\n    a/head: {zoom: 5}\n"), 6, "unknown key 'zoom'"},
      {WithArm("cameras:\n  streams:\n    a/head: [1]\n"), 6, "must be a mapping (width"},
      {WithArm("cameras:\n  streams:\n    a/head: {latency: {delay: 1, delay_steps: 2}}\n"), 6,
       "cameras.streams.a/head.latency: give the delay in steps or in seconds, not both"},
      {WithArm("cameras: {width: 640.5}\n"), 4, "cameras.width must be a whole number, not 640.5"},
      {WithArm("cameras:\n  height: 479.9\n"), 5, "cameras.height must be a whole number"},
      {WithArm("cameras: {samples: 2.5}\n"), 4, "cameras.samples must be a whole number"},
      {WithArm("cameras: {samples: 17}\n"), 4, "cameras.samples must be 0 to 16"},
      {WithArm("cameras:\n  streams:\n    a/head: {width: 10.5}\n"), 6, "whole number"},
      {WithArm("cameras: {}\ncameras: {}\n"), 5, "duplicate key 'cameras' in the scene"},
  };
  for (const Case& c : cases)
    testing::ExpectSceneRefusedAt(c.yaml, dir_ + "/s.yaml", c.line, c.message);
}

TEST_F(CameraSceneSections, GoodValuesReachTheCamerasSettings) {
  const world::SceneConfig s = world::ParseScene(
      WithArm("    cameras: [head, wrist]\n"
              "cameras:\n  enabled: true\n  width: 320\n  height: 240\n  rate: 15\n"
              "  modes: depth\n  gl: osmesa\n"
              "  streams:\n    a/head: {width: 64, modes: [rgb, instance],\n"
              "             latency: {delay_steps: 2}}\n    a/wrist:\n"),
      dir_ + "/s.yaml");
  const camera::CamerasConfig& c = camera::CamerasOf(s);
  EXPECT_EQ(c.width, 320);
  EXPECT_EQ(c.height, 240);
  EXPECT_EQ(c.rate, 15);
  EXPECT_EQ(c.modes, std::vector<std::string>{"depth"});
  EXPECT_EQ(c.gl, "osmesa");
  const camera::CameraSettings& head = c.cameras.at("a/head");
  EXPECT_EQ(head.width, 64);
  EXPECT_FALSE(head.height.has_value());
  EXPECT_EQ(*head.modes, (std::vector<std::string>{"rgb", "instance"}));
  ASSERT_TRUE(head.latency.has_value());
  EXPECT_EQ(head.latency->delay, 2);
  EXPECT_EQ(head.where.line, 13);
  EXPECT_FALSE(c.cameras.at("a/wrist").width.has_value());
  // A scene without the section has the defaults; a change made through EditCameras is the
  // scene's.
  world::SceneConfig plain = world::ParseScene(WithArm(""), dir_ + "/p.yaml");
  EXPECT_EQ(camera::CamerasOf(plain).width, 640);
  EXPECT_TRUE(camera::CamerasOf(plain).enabled);
  camera::EditCameras(plain).enabled = false;
  EXPECT_FALSE(camera::CamerasOf(plain).enabled);
}

// Two small models: a fixed-base arm with a camera, and a cart without one.
void WriteModels(const std::string& dir) {
  testing::WriteTextFile(dir, "arm.xml", R"(<mujoco>
  <worldbody>
    <body name="link"><joint name="hinge"/><geom size="0.1" mass="1"/>
      <camera name="eye" pos="0 0 1"/></body>
  </worldbody>
</mujoco>
)");
  testing::WriteTextFile(dir, "cart.xml", R"(<mujoco>
  <worldbody>
    <body name="cart" pos="3 0 0"><joint name="slide" type="slide"/><geom size="0.1" mass="1"/>
    </body>
  </worldbody>
</mujoco>
)");
}

TEST_F(CameraSceneSections, StreamsAreCheckedAgainstTheCompiledScene) {
  WriteModels(dir_);
  const std::string path = testing::WriteTextFile(
      dir_, "s.yaml",
      "articulations:\n  - {name: a, mjcf: arm.xml}\n  - {name: b, mjcf: cart.xml}\n"
      "cameras:\n"
      "  streams:\n"
      "    a/eye: {rate: 5}\n"      // 6: fine
      "    a/nose: {rate: 5}\n"     // 7
      "    b/mouth: {rate: 5}\n");  // 8
  const world::ValidationReport r = world::Validate(path);
  std::vector<std::string> errors;
  for (const auto& e : r.diagnostics.errors()) errors.push_back(e.str());
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("s.yaml:7: cameras.streams.a/nose: articulation 'a' has no camera "
                           "'nose' in its MJCF " +
                           dir_ + "/arm.xml (it has: eye)"),
            std::string::npos)
      << errors[0];
  EXPECT_NE(errors[1].find("s.yaml:8: cameras.streams.b/mouth: articulation 'b' has no camera "
                           "'mouth'"),
            std::string::npos)
      << errors[1];
  EXPECT_NE(errors[1].find("(it has: none)"), std::string::npos) << errors[1];
  // Begin-play (run, view, compile, bench) refuses the same scene.
  try {
    world::BuildCheckedScene(world::LoadSceneFile(path));
    FAIL() << "built it";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 7) << e.what();
    EXPECT_NE(std::string(e.what()).find("(and 1 more problem(s))"), std::string::npos) << e.what();
  }
  // The good stream alone passes.
  const std::string ok = testing::WriteTextFile(
      dir_, "ok.yaml",
      "articulations:\n  - {name: a, mjcf: arm.xml}\ncameras:\n  streams:\n    a/eye: {}\n");
  const world::ValidationReport good = world::Validate(ok);
  EXPECT_TRUE(good.ok()) << (good.diagnostics.errors().empty()
                                 ? ""
                                 : good.diagnostics.errors()[0].str());
}

}  // namespace
}  // namespace urlab
