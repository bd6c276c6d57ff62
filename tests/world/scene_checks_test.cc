// Every check begin-play runs is in world::CheckSceneConfig / CheckCompiledScene: `validate`
// collects them all (without starting or writing anything) and BuildCheckedScene (the manager,
// compile, run, bench) throws the first. Also the bad MJCF that composition used to run wrong:
// a short fromto under a placement and keyframes of the wrong length.
#include "urlab/world/scene_checks.h"

#include <filesystem>

#include "mujoco_test.h"
#include "urlab/world/manager.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

const std::string kArmPath = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";

class SceneChecksTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("scene_checks"); }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  // Error messages of `validate` for a scene file holding `yaml`.
  std::vector<std::string> ValidateErrors(const std::string& yaml) {
    const world::ValidationReport r = world::Validate(Write("s.yaml", yaml));
    std::vector<std::string> out;
    for (const auto& e : r.diagnostics.errors()) out.push_back(e.str());
    return out;
  }
  std::string dir_;
};

bool AnyContains(const std::vector<std::string>& v, const std::string& what) {
  for (const auto& s : v) {
    if (s.find(what) != std::string::npos) return true;
  }
  return false;
}

std::string Joined(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += s + "\n";
  return out;
}

TEST_F(SceneChecksTest, ValidateReportsEveryBeginPlayProblemAtOnce) {
  const std::string yaml =
      "articulations:\n"
      "  - name: a\n    mjcf: " +
      kArmPath +
      "\n"
      "    hold_keyframe: true\n"
      "  - name: a_b\n    mjcf: " +
      kArmPath + "\n";
  const auto errors = ValidateErrors(yaml);
  EXPECT_TRUE(AnyContains(errors, "s.yaml:5: articulation names 'a' and 'a_b' overlap"))
      << Joined(errors);
  EXPECT_TRUE(AnyContains(errors, "s.yaml:2: a: hold_keyframe needs an initial 'keyframe'"))
      << Joined(errors);
  // Begin-play refuses it too, with the first problem and the count of the rest.
  world::Manager manager;
  try {
    manager.BeginPlay(world::LoadSceneFile(dir_ + "/s.yaml"));
    FAIL() << "begin-play accepted it";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(and 1 more problem(s))"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(manager.playing());
}

TEST_F(SceneChecksTest, ControllerAndKeyframeNamesAreCheckedAgainstTheCompiledModel) {
  const std::string yaml =
      "articulations:\n"
      "  - name: a\n    mjcf: " +
      kArmPath +
      "\n"
      "    keyframe: lowered\n"
      "    controller:\n"
      "      type: pd\n"
      "      gains: {wrist: {kp: 10}, elbow: {kp: 5}, shoulder_motor: {kv: 1}}\n"
      "  - name: b\n    mjcf: " +
      kArmPath +
      "\n"
      "    controller:\n"
      "      type: keyframe\n"
      "      sequence: [{keyframe: raised}, {keyframe: waving}]\n";
  const auto errors = ValidateErrors(yaml);
  EXPECT_TRUE(AnyContains(errors, "s.yaml:2: a: keyframe 'lowered' is not in")) << Joined(errors);
  EXPECT_TRUE(AnyContains(errors,
                          "s.yaml:6: a: controller gains: no actuated joint or actuator "
                          "'wrist'"))
      << Joined(errors);
  EXPECT_FALSE(AnyContains(errors, "'elbow'")) << Joined(errors);           // a joint: fine
  EXPECT_FALSE(AnyContains(errors, "'shoulder_motor'")) << Joined(errors);  // an actuator: fine
  EXPECT_TRUE(AnyContains(errors, "s.yaml:11: b: controller sequence: keyframe 'waving'"))
      << Joined(errors);
  EXPECT_FALSE(AnyContains(errors, "'raised'")) << Joined(errors);
  EXPECT_EQ(errors.size(), 3u) << Joined(errors);
  EXPECT_THROW(world::BuildCheckedScene(world::LoadSceneFile(dir_ + "/s.yaml")), InputError);
}

// Two small models in `dir`: a fixed-base arm with a camera, and a cart.
void WriteBindingModels(const std::string& dir) {
  testing::WriteTextFile(dir, "arm.xml", R"(<mujoco>
  <worldbody>
    <body name="link"><joint name="hinge"/><geom size="0.1" mass="1"/>
      <camera name="eye" pos="0 0 1"/></body>
  </worldbody>
  <actuator><motor name="lift" joint="hinge"/></actuator>
</mujoco>
)");
  testing::WriteTextFile(dir, "cart.xml", R"(<mujoco>
  <worldbody>
    <body name="cart" pos="3 0 0"><joint name="slide" type="slide"/><geom size="0.1" mass="1"/></body>
  </worldbody>
  <actuator><motor name="drive" joint="slide"/></actuator>
</mujoco>
)");
}

TEST_F(SceneChecksTest, CamerasTwistAndInputBindingsAreCheckedAgainstTheCompiledModel) {
  // `run` and `view` used to refuse (or silently ignore) these only once subsystems started;
  // `validate` said OK.
  WriteBindingModels(dir_);
  const std::string yaml =
      "articulations:\n"
      "  - name: a\n"  // 2
      "    mjcf: arm.xml\n"
      "    cameras: [eye, nose]\n"
      "    twist: {max_vx: 1}\n"
      "    input:\n"
      "      - {actuator: lift, key: J}\n"              // 7: fine
      "      - {actuator: ghost, key: K}\n"             // 8
      "      - {actuator: hinge, key: L}\n"             // 9: a joint
      "      - {actuator: drive, key: M}\n"             // 10: b's actuator, short name
      "      - {actuator: b_drive, gamepad_axis: 1}\n"  // 11: b's actuator, full name
      "  - name: b\n"                                   // 12
      "    mjcf: cart.xml\n";
  // (The `cameras:` section's streams are the camera module's check through the section
  // registration: tests/camera/scene_settings_test.cc.)
  const auto errors = ValidateErrors(yaml);
  for (const std::string& want : {
           std::string("s.yaml:2: a.cameras: articulation 'a' has no camera 'nose'"),
           std::string("(it has: eye)"),
           std::string("s.yaml:2: a: twist needs a free base"),
           std::string("s.yaml:8: a.input: no actuator 'ghost'"),
           std::string("s.yaml:9: a.input: no actuator 'hinge'"),
           std::string("'hinge' is a joint: name the actuator that drives it"),
           std::string("s.yaml:10: a.input: no actuator 'drive'"),
           std::string("s.yaml:11: a.input: no actuator 'b_drive'"),
           std::string("it is an actuator of articulation 'b'"),
           std::string("(its actuators: lift)"),
       }) {
    EXPECT_TRUE(AnyContains(errors, want)) << want << " missing in:\n" << Joined(errors);
  }
  EXPECT_EQ(errors.size(), 6u) << Joined(errors);
  // Begin-play (run, view, compile, bench) refuses the same scene.
  try {
    world::BuildCheckedScene(world::LoadSceneFile(dir_ + "/s.yaml"));
    FAIL() << "built it";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("(and 5 more problem(s))"), std::string::npos) << e.what();
  }
  // The good bindings alone pass.
  Write("ok.yaml",
        "articulations:\n  - name: a\n    mjcf: arm.xml\n    cameras: [eye]\n"
        "    input:\n      - {actuator: lift, key: Space}\n");
  const world::ValidationReport ok = world::Validate(dir_ + "/ok.yaml");
  EXPECT_TRUE(ok.ok()) << (ok.diagnostics.errors().empty() ? "" : ok.diagnostics.errors()[0].str());
}

TEST_F(SceneChecksTest, ALooseObjectInAFixedArmsFileIsNotAFreeBaseForTwist) {
  // The ball's free joint used to count as the arm's free base: `twist:` passed and drove the
  // ball (physics/free_base.h).
  testing::WriteTextFile(dir_, "arm_and_ball.xml", R"(<mujoco>
  <worldbody>
    <body name="link"><joint name="hinge"/><geom size="0.1" mass="1"/>
      <body name="tip" pos="0 0 0.3"><joint name="wrist"/><geom size="0.05" mass="1"/></body>
    </body>
    <body name="ball" pos="1 0 0.1"><freejoint name="ball_free"/><geom size="0.05"/></body>
  </worldbody>
</mujoco>
)");
  const auto errors = ValidateErrors(
      "articulations:\n  - name: a\n    mjcf: arm_and_ball.xml\n    twist: {max_vx: 1}\n");
  EXPECT_TRUE(AnyContains(errors, "s.yaml:2: a: twist needs a free base")) << Joined(errors);
}

TEST_F(SceneChecksTest, ValidateStartsNothingAndWritesNothing) {
  const std::string yaml =
      "articulations:\n  - {name: a, mjcf: " + kArmPath + "}\nsave_debug_xml: debug_out\n";
  const world::ValidationReport r = world::Validate(Write("s.yaml", yaml));
  EXPECT_TRUE(r.ok()) << Joined({r.diagnostics.all().empty() ? "" : r.diagnostics.all()[0].str()});
  EXPECT_FALSE(fs::exists(dir_ + "/debug_out"));
  // Building it for real does write the debug files (atomically, folder created).
  world::BuildCheckedScene(world::LoadSceneFile(dir_ + "/s.yaml"));
  EXPECT_TRUE(fs::exists(dir_ + "/debug_out/scene_compiled.xml"));
  EXPECT_TRUE(fs::exists(dir_ + "/debug_out/scene_compiled.mjb"));
}

TEST_F(SceneChecksTest, ShortFromToUnderAPlacementIsRefusedNotReadPastItsEnd) {
  // A fromto of five numbers under a placement: MuJoCo's parser refuses it, at its line (the
  // composition once read past its end).
  Write("stick.xml", R"(<mujoco>
  <worldbody>
    <geom type="capsule" size="0.05" fromto="0 0 0 0 0"/>
  </worldbody>
</mujoco>
)");
  Write("s.yaml", "articulations:\n  - {name: s, mjcf: stick.xml, pos: [1, 0, 0]}\n");
  try {
    world::BuildCheckedScene(world::LoadSceneFile(dir_ + "/s.yaml"));
    FAIL() << "composed a 5-number fromto";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), dir_ + "/stick.xml:3") << e.what();
    EXPECT_NE(std::string(e.what()).find("'fromto' does not have enough data"), std::string::npos)
        << e.what();
  }
  // The same through a default class.
  Write("stick2.xml", R"(<mujoco>
  <default><geom fromto="0 0 0 1"/></default>
  <worldbody><geom type="capsule" size="0.05"/></worldbody>
</mujoco>
)");
  Write("s2.yaml", "articulations:\n  - {name: s, mjcf: stick2.xml, euler: [0, 0, 90]}\n");
  EXPECT_THROW(world::BuildCheckedScene(world::LoadSceneFile(dir_ + "/s2.yaml")), InputError);
  EXPECT_FALSE(world::Validate(dir_ + "/s2.yaml").ok());
}

TEST_F(SceneChecksTest, KeyframesOfTheWrongLengthAreRefusedAsCompileRefusesThem) {
  // MuJoCo refuses a key longer than the model when it attaches the articulation, naming neither
  // file nor line; the check does, for every such key. A shorter key MuJoCo fills from the
  // reference configuration, as it does for the file alone.
  const std::string model = Write("two.xml", R"(<mujoco>
  <worldbody>
    <body><joint name="j1"/><geom size="0.1"/>
      <body pos="0 0 1"><joint name="j2"/><geom size="0.1"/></body></body>
  </worldbody>
  <keyframe>
    <key name="short" qpos="0.5"/>
    <key name="long" qpos="0.1 0.2 0.3"/>
    <key name="good" qpos="0.1 0.2"/>
    <key name="longer" qpos="0.1 0.2 0.3 0.4" ctrl="1"/>
  </keyframe>
</mujoco>
)");
  // A single MJCF file takes the scene path: validate reports the keys at their lines.
  const world::ValidationReport r = world::Validate(model);
  std::vector<std::string> errors;
  for (const auto& e : r.diagnostics.errors()) errors.push_back(e.str());
  EXPECT_TRUE(AnyContains(errors,
                          "two.xml:8: two: keyframe 'long': qpos has 3 value(s), the "
                          "model has nq=2"))
      << Joined(errors);
  EXPECT_TRUE(AnyContains(errors, "two.xml:10: two: keyframe 'longer': qpos has 4 value(s)"))
      << Joined(errors);
  EXPECT_TRUE(AnyContains(errors, "two.xml:10: two: keyframe 'longer': ctrl has 1 value(s)"))
      << Joined(errors);
  EXPECT_EQ(errors.size(), 3u) << Joined(errors);
  // ... and begin-play (what `urlab run` does) refuses it.
  world::Manager manager;
  EXPECT_THROW(manager.BeginPlay(world::LoadSceneOrModel(model)), InputError);
}

TEST_F(SceneChecksTest, TheBundledScenesPassEveryCheck) {
  for (const char* scene : {"examples/scenes/two_arms.yaml", "examples/scenes/humanoid_pd.yaml",
                            "examples/models/pendulum_arm.xml", "examples/models/servo_arm.xml"}) {
    const world::ValidationReport r = world::Validate(testing::SourcePath(scene));
    EXPECT_TRUE(r.ok()) << scene << ": "
                        << (r.diagnostics.errors().empty() ? "" : r.diagnostics.errors()[0].str());
  }
}

}  // namespace
}  // namespace urlab
