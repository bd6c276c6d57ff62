// Scene files refuse bad input at its file:line: duplicate and non-string keys, numbers out of
// range, sections of features that do not exist yet, files that are not regular files; relative
// paths in a symlinked scene folder resolve from the folder the user named.
#include "urlab/world/scene_file.h"

#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "scene_errors.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;

class SceneFileTest : public testing::MujocoTest {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("scene_file"); }
  std::string dir_;
};

using testing::kArm;
using testing::WithArm;

TEST_F(SceneFileTest, BadInputIsRefusedAtItsLine) {
  struct Case {
    std::string yaml;
    int line;
    const char* message;
  };
  const Case cases[] = {
      // duplicate keys (yaml-cpp would keep the first silently)
      {WithArm("    pos: [0, 0, 1]\n    pos: [0, 0, 2]\n"), 5, "duplicate key 'pos'"},
      {WithArm("options: {timestep: 0.002, timestep: 0.001}\n"), 4, "duplicate key 'timestep'"},
      {WithArm("    controller:\n      type: pd\n      gains:\n        shoulder: {kp: 1}\n"
               "        shoulder: {kp: 2}\n"),
       8, "duplicate key 'shoulder' in controller.gains (first at line 7)"},
      // keys that are not strings
      {WithArm("[1, 2]: x\n"), 4, "keys in the scene must be names"},
      {WithArm("    ~: 3\n"), 4, "must be names"},
      {WithArm("options: {? {a: 1} : 2}\n"), 4, "must be names"},
      // numbers out of range
      {WithArm("    controller: {type: pd, kp: .nan}\n"), 4, "controller.kp must be >= 0"},
      {WithArm("    controller: {type: pd, kv: -1}\n"), 4, "controller.kv must be >= 0"},
      {WithArm("    controller: {type: pd, torque_limit: -5}\n"), 4, "torque_limit must be >= 0"},
      {WithArm("    controller: {type: pd, torque_limit: .nan}\n"), 4, "torque_limit must be"},
      {WithArm("    controller: {type: pd, kp: .inf}\n"), 4, "and finite"},
      {WithArm("    controller: {type: pd, gains: {elbow: {kp: -3}}}\n"), 4, "gains.elbow.kp"},
      {WithArm("    controller:\n      type: keyframe\n      sequence:\n"
               "        - {keyframe: raised, blend: -1}\n"),
       7, "blend must be >= 0"},
      {WithArm("    pos: [0, .nan, 0]\n"), 4, "pos must be"},
      {WithArm("    quat: [0, 0, 0, 0]\n"), 4, "quat must not be zero"},
      {WithArm("options: {timestep: 0}\n"), 4, "timestep: 0 is out of range (expected > 0"},
      {WithArm("options:\n  timestep: -0.001\n"), 5, "out of range"},
      {WithArm("options: {timestep: inf}\n"), 4, "out of range"},
      {WithArm("options: {timestep: .inf}\n"), 4, "not a list of numbers"},
      {WithArm("options: {timestep: .nan}\n"), 4, "not a list of numbers"},
      {WithArm("options: {timestepp: 0.001}\n"), 4, "unknown options 'timestepp'"},
      {WithArm("options: {flag: {gravity: off}}\n"), 4, "invalid keyword 'off'"},
      {WithArm("size: {nstack: 1e30}\n"), 4, "nstack"},
      {WithArm("size: {nstack: 99999999999}\n"), 4, "out of the range of an int"},
      {WithArm("size: {njmax: -2}\n"), 4, "out of range"},
      {WithArm("size: {nconmax: 1.5}\n"), 4, "integers"},
      {WithArm("size: {nstack: [1, 2]}\n"), 4, "must be an integer"},
      // twist and input bindings
      {WithArm("    twist: {max_vx: -1}\n"), 4, "a.twist.max_vx must be >= 0"},
      {WithArm("    twist: {max_vz: 1}\n"), 4, "max_vz"},
      {WithArm("    twist: {mode: walk}\n"), 4, "a.twist.mode must be policy, gait or hover"},
      // gait controller fields
      {WithArm("    controller: {type: pd, period: 0.3}\n"), 4,
       "controller.period applies to a gait controller"},
      {WithArm("    controller: {type: gait, period: 0}\n"), 4, "controller.period"},
      {WithArm("    controller: {type: gait, swing_height: -0.1}\n"), 4, "controller.swing_height"},
      {WithArm("    controller: {type: gait, stance_height: 0}\n"), 4, "controller.stance_height"},
      {WithArm("    controller: {type: trot}\n"), 4, "none, pd, passthrough, keyframe or gait"},
      {WithArm("    input:\n      - {actuator: shoulder, key: J, gamepad_axis: 1}\n"), 5,
       "exactly one of key, gamepad_axis, gamepad_button"},
      {WithArm("    input:\n      - {key: J}\n"), 5, "a binding needs an actuator"},
      {WithArm("    input:\n      - {actuator: shoulder, gamepad_axis: 6}\n"), 5,
       "gamepad_axis must be"},
      {WithArm("    input:\n      - {actuator: shoulder, gamepad_button: 1.5}\n"), 5,
       "whole number"},
      {WithArm("    input: {actuator: shoulder}\n"), 4, "must be a list"},
      // features that do not exist yet
      {WithArm("props:\n  - {mesh: box.obj}\n"), 5, "a prop needs a name"},
      {WithArm("terrain: {file: h.png}\n"), 4, "terrain must be a list"},
      // an articulation's own cameras (the `cameras:` section is the camera module's:
      // tests/camera/scene_settings_test.cc)
      {WithArm("    cameras: maybe\n"), 4, "true, false or a list of camera names"},
      {WithArm("recording: {file: r.bin}\n"), 4, "'recording:' is not a scene section"},
      // a section no subsystem registered: AnUnregisteredSubsystemSectionNamesItsRegistration
      // impulse launchers
      {WithArm("launchers: {name: gun}\n"), 4, "launchers must be a list"},
      {WithArm("launchers:\n  - {pos: [0, 0, 1]}\n"), 5, "a launcher needs a name"},
      {WithArm("launchers:\n  - {name: gun, shape: cone}\n"), 5,
       "gun.shape must be sphere, box or capsule, not 'cone'"},
      {WithArm("launchers:\n  - {name: gun, shape: box, size: [0.1, 0.1]}\n"), 5,
       "a box needs 3 number(s) (half sizes x y z), not 2"},
      {WithArm("launchers:\n  - {name: gun, size: 0}\n"), 5, "gun.size must be > 0"},
      {WithArm("launchers:\n  - {name: gun, mass: -1}\n"), 5, "gun.mass must be > 0"},
      {WithArm("launchers:\n  - {name: gun, speed: .nan}\n"), 5, "gun.speed must be 0 to 1000"},
      {WithArm("launchers:\n  - {name: gun, pool: 0}\n"), 5, "gun.pool must be 1 to 64"},
      {WithArm("launchers:\n  - {name: gun, pool: 65}\n"), 5, "gun.pool must be 1 to 64"},
      {WithArm("launchers:\n  - {name: gun, pool: 2.5}\n"), 5, "whole number"},
      {WithArm("launchers:\n  - {name: gun, rgba: [1, 0, 0, 2]}\n"), 5, "rgba values must be"},
      {WithArm("launchers:\n  - {name: gun, quat: [1, 0, 0, 0], euler: [0, 0, 0]}\n"), 5,
       "at most one of quat, euler, axisangle"},
      {WithArm("launchers:\n  - {name: gun, direction: [1, 0, 0]}\n"), 5,
       "unknown key 'direction' in launcher"},
      {WithArm("launchers:\n  - {name: a}\n"), 5, "the name 'a' is used twice"},
      // newer keys: whole numbers, key names (these were accepted or truncated; the network's
      // ports: tests/net/scene_settings_test.cc)
      {WithArm("    input:\n      - {actuator: shoulder_motor, key: F13}\n"), 5,
       "unknown key 'F13'"},
      {WithArm("    input:\n      - {actuator: shoulder_motor, key: \"\"}\n"), 5, "an empty key"},
      // names: a documented character set
      {"articulations:\n  - name: \"a\\nb\"\n    mjcf: " + kArm + "\n", 2,
       "articulation name 'a\\nb' contains a newline"},
      {"articulations:\n  - name: \"a b\"\n    mjcf: " + kArm + "\n", 2, "contains a space"},
      {"articulations:\n  - {name: a/b, mjcf: " + kArm + "}\n", 2, "contains '/'"},
      {"articulations:\n  - {name: \"\", mjcf: " + kArm + "}\n", 2, "is empty"},
      {"articulations:\n  - {name: 1arm, mjcf: " + kArm + "}\n", 2,
       "must start with a letter or '_'"},
      {"articulations:\n  - {name: \"arm\\t\", mjcf: " + kArm + "}\n", 2, "contains a tab"},
      {WithArm("launchers:\n  - {name: \"gun\\r\"}\n"), 5, "launcher name"},
      {WithArm("props:\n  - {name: \"p\\u00e9\", mesh: x.stl}\n"), 5, "non-ASCII"},
  };
  for (const Case& c : cases)
    testing::ExpectSceneRefusedAt(c.yaml, dir_ + "/s.yaml", c.line, c.message);
}

// Issue 38, case 9: a scene's seed is a whole number a double holds exactly, as the step
// server's and the batch's seeds (2^53 was accepted here and refused there).
TEST_F(SceneFileTest, TheSeedHasTheServersRange) {
  testing::ExpectSceneRefusedAt(WithArm("seed: 9007199254740992\n"), dir_ + "/s.yaml", 4,
                                "seed must be 0 to 9007199254740991");
  testing::ExpectSceneRefusedAt(WithArm("seed: 18446744073709551616\n"), dir_ + "/s.yaml", 4,
                                "seed must be 0 to 9007199254740991");
  EXPECT_EQ(world::ParseScene(WithArm("seed: 9007199254740991\n"), dir_ + "/s.yaml").seed,
            9007199254740991ull);
}

// The subsystems' sections are parsed by the modules above world once a program registers them
// (the `urlab` tool registers all); a program that did not is told which registration is missing.
TEST_F(SceneFileTest, AnUnregisteredSubsystemSectionNamesItsRegistration) {
  const std::string path = dir_ + "/s.yaml";
  testing::ExpectSceneRefusedAt(WithArm("network: {rpc: \"tcp://127.0.0.1:*\"}\n"), path, 4,
                                "'network:' is a section of urlab::net (call "
                                "urlab::net::RegisterSceneSections()), which this program did "
                                "not register");
  testing::ExpectSceneRefusedAt(WithArm("seed: 1\ncameras: {}\n"), path, 5,
                                "urlab::camera::RegisterSceneSections()");
  testing::ExpectSceneRefusedAt(WithArm("viewer: {}\n"), path, 4,
                                "urlab::viewer::RegisterSceneSections()");
  testing::ExpectSceneRefusedAt(WithArm("cinematic: {}\n"), path, 4,
                                "urlab::viewer::RegisterSceneSections()");
  testing::ExpectSceneRefusedAt(WithArm("netwrok: {}\n"), path, 4,
                                "unknown key 'netwrok' in the scene");  // a typo: unknown
}

TEST_F(SceneFileTest, GoodValuesStillPass) {
  const world::SceneConfig s =
      world::ParseScene(WithArm("    controller: {type: pd, kp: 0, kv: 0, torque_limit: .inf}\n"
                                "options: {timestep: 0.001, flag: {gravity: disable}}\n"
                                "size: {nstack: 5000000, njmax: -1}\n"),
                        dir_ + "/s.yaml");
  EXPECT_EQ(s.size.at("nstack"), "5000000");
  EXPECT_EQ(s.options.at("timestep"), "0.001");
  EXPECT_EQ(s.options.at("flag.gravity"), "disable");
  const world::SceneConfig t =
      world::ParseScene(WithArm("    control_source: input\n    twist: {max_vx: 2, yaw_gain: 1}\n"
                                "    input:\n      - {actuator: shoulder, key: J, scale: -0.5}\n"
                                "      - {actuator: shoulder, gamepad_axis: 3}\n"),
                        dir_ + "/t.yaml");
  const world::ArticulationConfig& a = t.articulations.at(0);
  EXPECT_EQ(a.control_source, world::ControlSource::kInput);
  EXPECT_TRUE(a.twist_given);
  EXPECT_EQ(a.twist.max_vx, 2);
  EXPECT_EQ(a.twist.yaw_gain, 1);
  EXPECT_EQ(a.twist.max_vy, control::TwistSettings{}.max_vy);
  EXPECT_FALSE(a.twist_mode_given) << "resolved when installed (gait or policy)";
  ASSERT_EQ(a.input.size(), 2u);
  EXPECT_EQ(a.input[0].key, "J");
  EXPECT_EQ(a.input[0].scale, -0.5);
  EXPECT_EQ(a.input[1].gamepad_axis, 3);
  EXPECT_EQ(a.input[1].where.line, 8);
  const world::SceneConfig gs = world::ParseScene(
      WithArm("    controller: {type: gait, kp: 80, period: 0.5, swing_height: 0.05,\n"
              "                 stance_height: 0.3, step_gain: 0.1}\n"
              "    twist: {mode: hover}\n"),
      dir_ + "/g.yaml");
  const world::ArticulationConfig& ga = gs.articulations.at(0);
  EXPECT_EQ(ga.controller.type, "gait");
  EXPECT_EQ(ga.controller.defaults.kp, 80);
  EXPECT_EQ(ga.controller.gait.period, 0.5);
  EXPECT_EQ(ga.controller.gait.swing_height, 0.05);
  EXPECT_EQ(ga.controller.gait.stance_height, 0.3);
  EXPECT_EQ(ga.controller.gait.step_gain, 0.1);
  EXPECT_TRUE(ga.twist_mode_given);
  EXPECT_EQ(ga.twist.mode, control::TwistMode::kHover);
  const world::SceneConfig l = world::ParseScene(
      WithArm("launchers:\n  - {name: gun, pos: [1, 2, 3], shape: capsule, size: [0.02, 0.1],\n"
              "     mass: 0.2, speed: 12, pool: 64, axisangle: [0, 0, 1, 90]}\n"),
      dir_ + "/l.yaml");
  ASSERT_EQ(l.launchers.size(), 1u);
  const world::LauncherSpec& g = l.launchers[0].spec;
  EXPECT_EQ(g.shape, "capsule");
  EXPECT_EQ(g.size, (std::vector<double>{0.02, 0.1}));
  EXPECT_EQ(g.pool, 64);
  EXPECT_EQ(g.speed, 12);
  EXPECT_NEAR(g.quat[3], std::sqrt(0.5), 1e-12);
  EXPECT_EQ(l.launchers[0].where.line, 5);
}

TEST_F(SceneFileTest, ArticulationCameras) {
  const world::SceneConfig s =
      world::ParseScene(WithArm("    cameras: [head, wrist]\n"), dir_ + "/s.yaml");
  EXPECT_EQ(s.articulations[0].cameras, (std::vector<std::string>{"head", "wrist"}));
  EXPECT_FALSE(s.articulations[0].all_cameras);
  EXPECT_TRUE(world::ParseScene(WithArm("    cameras: true\n"), dir_ + "/t.yaml")
                  .articulations[0]
                  .all_cameras);
}

TEST_F(SceneFileTest, ScenePathsMustBeRegularFiles) {
  const std::string fifo = dir_ + "/pipe.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    world::LoadSceneFile(fifo);
    FAIL() << "a FIFO was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("FIFO"), std::string::npos) << e.what();
  }
  EXPECT_THROW(world::LoadSceneOrModel("/dev/zero"), InputError);
  EXPECT_THROW(world::LoadSceneOrModel(dir_), InputError);
  // An articulation's mjcf that is a device: located at the scene's mjcf line.
  try {
    world::ParseScene("articulations:\n  - name: a\n    mjcf: /dev/zero\n", dir_ + "/s.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 3) << e.what();
    EXPECT_NE(std::string(e.what()).find("a device"), std::string::npos) << e.what();
  }
  // Absurdly large scene files are refused from their size.
  const std::string big = dir_ + "/big.yaml";
  std::ofstream(big) << "articulations: []\n";
  fs::resize_file(big, (64u << 20) + 1);
  try {
    world::LoadSceneFile(big);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("larger than"), std::string::npos) << e.what();
  }
}

TEST_F(SceneFileTest, SymlinkedSceneFolderResolvesFromTheLinksFolder) {
  // project/models/arm.xml and project/scenes -> elsewhere/scenes (a symlinked folder): the
  // scene's "../models/arm.xml" means project/models, the folder next to the link.
  const std::string project = dir_ + "/project";
  const std::string elsewhere = dir_ + "/elsewhere";
  fs::create_directories(project + "/models");
  fs::create_directories(elsewhere + "/scenes");
  fs::copy_file(kArm, project + "/models/arm.xml");
  testing::WriteTextFile(elsewhere, "scenes/s.yaml",
                         "articulations:\n  - {name: a, mjcf: ../models/arm.xml}\n");
  fs::create_directory_symlink(elsewhere + "/scenes", project + "/scenes");
  const world::SceneConfig s = world::LoadSceneFile(project + "/scenes/s.yaml");
  EXPECT_EQ(s.articulations.at(0).mjcf, project + "/models/arm.xml");
  EXPECT_EQ(s.path, project + "/scenes/s.yaml");
}

TEST_F(SceneFileTest, ASingleMjcfFileIsASceneOfOneArticulation) {
  const world::SceneConfig s = world::LoadSceneOrModel(kArm);
  ASSERT_EQ(s.articulations.size(), 1u);
  EXPECT_EQ(s.articulations[0].name, "pendulum_arm");
  EXPECT_EQ(s.articulations[0].mjcf, kArm);
}

}  // namespace
}  // namespace urlab
