// A cube texture given as six separate files (fileright ... fileback) in an articulation that
// lives in another folder than the scene: its files are found when the scene is composed and
// compiled, and the scene's MJCF written back names them so that it loads again.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "mujoco_test.h"
#include "urlab/mjcf/spec.h"
#include "urlab/physics/model.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

constexpr const char* kCubeRobot = R"(<mujoco model="cube_box">
  <compiler texturedir="textures"/>
  <asset>
    <texture name="faces" type="cube" fileright="face_right.png" fileleft="face_left.png"
             fileup="face_up.png" filedown="face_down.png" filefront="face_front.png"
             fileback="face_back.png"/>
    <material name="paint" texture="faces"/>
  </asset>
  <worldbody>
    <body name="box" pos="0 0 0.5">
      <freejoint/>
      <geom type="box" size="0.1 0.1 0.1" material="paint"/>
    </body>
  </worldbody>
</mujoco>)";

class CubeTextureTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("cube_texture");
    const std::string faces = testing::TestData("mjcf/corpus/assets/textures");
    fs::create_directories(dir_ + "/robots/box/textures");
    for (const char* side : {"right", "left", "up", "down", "front", "back"}) {
      const std::string name = std::string("face_") + side + ".png";
      fs::copy_file(faces + "/" + name, dir_ + "/robots/box/textures/" + name);
    }
    robot_ = testing::WriteTextFile(dir_, "robots/box/robot.xml", kCubeRobot);
    scene_ = testing::WriteTextFile(
        dir_, "scenes/scene.yaml",
        "articulations:\n  - name: box\n    mjcf: ../robots/box/robot.xml\n");
  }
  std::string dir_, robot_, scene_;
};

TEST_F(CubeTextureTest, SixSeparateFilesComposeCompileAndAreWrittenBack) {
  // MuJoCo's own load of the robot in its folder: the texture the scene must have.
  const physics::ModelPtr alone = physics::LoadXmlFile(robot_);
  ASSERT_EQ(alone->ntex, 1);

  const world::CompiledScene scene = world::BuildScene(world::LoadSceneFile(scene_));
  const mjModel* m = scene.model.get();
  const int tex = mj_name2id(m, mjOBJ_TEXTURE, "box_faces");
  ASSERT_GE(tex, 0);
  ASSERT_EQ(m->tex_width[tex], alone->tex_width[0]);
  ASSERT_EQ(m->tex_height[tex], alone->tex_height[0]);
  const std::size_t bytes = static_cast<std::size_t>(m->tex_width[tex]) * m->tex_height[tex] *
                            static_cast<std::size_t>(m->tex_nchannel[tex]);
  EXPECT_EQ(0,
            std::memcmp(m->tex_data + m->tex_adr[tex], alone->tex_data + alone->tex_adr[0], bytes));

  // Written back with absolute paths: every side names its file where it is.
  const std::string xml = world::SceneXml(scene);
  for (const char* side : {"right", "left", "up", "down", "front", "back"}) {
    const std::string file =
        (fs::path(dir_) / "robots/box/textures" / (std::string("face_") + side + ".png"))
            .lexically_normal()
            .string();
    EXPECT_NE(xml.find(std::string("file") + side + "=\"" + file + "\""), std::string::npos)
        << side << " in\n"
        << xml;
  }
  // Saved in a third folder with paths relative to it, it loads as it was composed.
  const std::string out_dir = dir_ + "/exported";
  const std::string saved =
      testing::WriteTextFile(out_dir, "scene.xml", world::SceneXml(scene, nullptr, out_dir));
  EXPECT_NE(
      testing::ReadTextFile(saved).find("fileright=\"../robots/box/textures/face_right.png\""),
      std::string::npos);
  const physics::ModelPtr again = physics::LoadXmlFile(saved);
  const int tex2 = mj_name2id(again.get(), mjOBJ_TEXTURE, "box_faces");
  ASSERT_GE(tex2, 0);
  EXPECT_EQ(
      0, std::memcmp(again->tex_data + again->tex_adr[tex2], m->tex_data + m->tex_adr[tex], bytes));
}

TEST_F(CubeTextureTest, TheSixFilesAreInputsOfTheScene) {
  const std::vector<std::string> inputs = mjcf::ModelInputFiles(robot_);
  for (const char* side : {"right", "left", "up", "down", "front", "back"}) {
    const std::string file =
        (fs::path(dir_) / "robots/box/textures" / (std::string("face_") + side + ".png"))
            .lexically_normal()
            .string();
    EXPECT_NE(std::find(inputs.begin(), inputs.end(), file), inputs.end()) << file;
  }
}

}  // namespace
}  // namespace urlab
