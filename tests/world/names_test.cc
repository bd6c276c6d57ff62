// Names users give: a bare MJCF file's articulation name, and short or full names of keyframes,
// joints and actuators accepted everywhere, with ambiguous short names refused listing the
// candidates (world/names.h), through the scene file, the session and the lookup itself.
#include "urlab/world/names.h"

#include <string>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

// An arm with two keyframes; `model` is its <mujoco model> attribute ("" for none).
std::string Arm(const std::string& model) {
  return "<mujoco" + (model.empty() ? std::string() : " model=\"" + model + "\"") + R"(>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" axis="0 1 0" range="-1 1" limited="true"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.05"/>
      <body name="lower" pos="0.5 0 0">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="shoulder_motor" joint="shoulder" ctrlrange="-1 1" ctrllimited="true"/>
    <motor name="elbow_motor" joint="elbow" ctrlrange="-1 1" ctrllimited="true"/>
  </actuator>
  <keyframe>
    <key name="home" qpos="0.5 -0.25"/>
    <key name="rest" qpos="0 0"/>
  </keyframe>
</mujoco>
)";
}

class NamesTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("names"); }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  // Two copies of the arm, "a" and "b", with `extra` YAML under a.
  world::SceneConfig TwoArms(const std::string& extra_a = "") {
    Write("arm.xml", Arm("arm"));
    return world::ParseScene("articulations:\n  - name: a\n    mjcf: arm.xml\n" + extra_a +
                                 "  - name: b\n    mjcf: arm.xml\n    pos: [0, 2, 0]\n",
                             dir_ + "/scene.yaml");
  }
  std::string dir_;
};

TEST_F(NamesTest, ABareFileIsNamedAfterItsModelOrItsFolderForSceneXml) {
  // Every public robot ships a scene.xml: its folder names it, not "scene".
  const std::string scene = Write("go2/scene.xml", Arm("go2 scene"));
  EXPECT_EQ(world::LoadSceneOrModel(scene).articulations.at(0).name, "go2");
  // Otherwise the model's name (letters and digits; the rest become '_', trimmed).
  const std::string named = Write("robots/v3_final.xml", Arm("Spot arm (v3)"));
  EXPECT_EQ(world::LoadSceneOrModel(named).articulations.at(0).name, "Spot_arm__v3");
  // A model without a name: the file stem, as before.
  const std::string unnamed = Write("my-arm.xml", Arm(""));
  EXPECT_EQ(world::LoadSceneOrModel(unnamed).articulations.at(0).name, "my_arm");
  EXPECT_EQ(world::ModelArticulationName("/x/...xml", "!!!"), "model");
  // The articulation runs under that name: its elements carry the prefix.
  const auto session = world::Session::Create(world::LoadSceneOrModel(scene));
  EXPECT_NE(session->FindArticulation("go2"), nullptr);
  EXPECT_GE(mj_name2id(session->engine().model(), mjOBJ_JOINT, "go2_shoulder"), 0);
}

TEST_F(NamesTest, ShortAndFullNamesResolveWithinAnArticulation) {
  const world::CompiledScene s = world::BuildScene(TwoArms());
  const mjModel* m = s.model.get();
  const int a_home = mj_name2id(m, mjOBJ_KEY, "a_home");
  ASSERT_GE(a_home, 0);
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, "a_", "home"), a_home);
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, "a_", "a_home"), a_home);  // full: always accepted
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, "a_", "b_home"), -1);      // another's: not here
  EXPECT_EQ(world::FindNamed(m, mjOBJ_ACTUATOR, "b_", "elbow_motor"),
            mj_name2id(m, mjOBJ_ACTUATOR, "b_elbow_motor"));
  EXPECT_EQ(world::ShortNameOf(m, mjOBJ_KEY, a_home, "a_"), "home");
  EXPECT_EQ(world::ShortNames(m, mjOBJ_KEY, "b_"), (std::vector<std::string>{"home", "rest"}));
  try {
    world::RequireNamed(m, mjOBJ_KEY, "a_", "sit", "articulation 'a'");
    FAIL() << "a missing keyframe was found";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "no keyframe 'sit' in articulation 'a' (it has: home, rest)");
  }
}

TEST_F(NamesTest, AShortNameTwoArticulationsShareIsAmbiguousSceneWide) {
  const world::CompiledScene s = world::BuildScene(TwoArms());
  const mjModel* m = s.model.get();
  const std::vector<std::string> prefixes = {"a_", "b_"};
  try {
    world::FindNamed(m, mjOBJ_KEY, prefixes, "home");
    FAIL() << "an ambiguous short name was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(),
                 "keyframe name 'home' is ambiguous: it could be a_home, b_home; give the full "
                 "name");
  }
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, prefixes, "b_home"), mj_name2id(m, mjOBJ_KEY, "b_home"));
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, prefixes, "nope"), -1);
  // Unique short names resolve scene-wide too.
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, std::vector<std::string>{"b_"}, "rest"),
            mj_name2id(m, mjOBJ_KEY, "b_rest"));
}

TEST_F(NamesTest, AShortNameCanBeAmbiguousWithinOneArticulation) {
  // Articulation "a" has keys "home" and "a_home": "a_home" is then its own key's short name
  // and the full name of "home".
  std::string xml = Arm("arm");
  xml.replace(xml.find("<key name=\"rest\""), 16, "<key name=\"a_home\"");
  Write("arm.xml", xml);
  const world::CompiledScene s = world::BuildScene(
      world::ParseScene("articulations:\n  - {name: a, mjcf: arm.xml}\n", dir_ + "/scene.yaml"));
  const mjModel* m = s.model.get();
  EXPECT_THROW(world::FindNamed(m, mjOBJ_KEY, "a_", "a_home"), Error);
  EXPECT_EQ(world::FindNamed(m, mjOBJ_KEY, "a_", "a_a_home"), mj_name2id(m, mjOBJ_KEY, "a_a_home"));
}

TEST_F(NamesTest, TheSceneFileAndTheSessionTakeShortOrFullNames) {
  // Initial keyframe, PD gains and keyframe-controller steps, each given in full.
  const world::SceneConfig scene = TwoArms(
      "    keyframe: a_home\n"
      "    controller:\n"
      "      type: keyframe\n"
      "      gains: {a_shoulder: {kp: 50}, elbow_motor: {kp: 20}}\n"
      "      sequence: [{keyframe: a_rest}, {keyframe: home}]\n");
  const auto session = world::Session::Create(scene);
  const world::Articulation& a = session->Require("a");
  EXPECT_EQ(a.initial_key, mj_name2id(session->engine().model(), mjOBJ_KEY, "a_home"));
  // Resets by short or full name, only among the articulation's own keyframes.
  EXPECT_GT(session->ResetArticulation("a", "rest"), 0u);
  EXPECT_GT(session->ResetArticulation("a", "a_rest"), 0u);
  try {
    session->ResetArticulation("a", "b_rest");
    FAIL() << "another articulation's keyframe was accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "no keyframe 'b_rest' in articulation 'a' (it has: home, rest)");
  }
}

TEST_F(NamesTest, ABadNameInTheSceneFileNamesTheArticulation) {
  try {
    world::Session::Create(TwoArms("    keyframe: sit\n"));
    FAIL() << "a missing keyframe was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a: keyframe 'sit' is not in"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace urlab
