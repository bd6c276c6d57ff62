// `validate` reports what `run` refuses, with file:line, and `run` refuses what `validate`
// reports: the newer scene keys (cameras, camera ports, twist, input bindings), infinite values,
// files that are not files, prop and terrain errors at their scene line, engine errors while
// compiling; validate writes nothing, not even into the cache; a diverging run stops with exit
// 1 as its --help says; a paced run that cannot keep up says so, once in a while.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "mujoco_test.h"
#include "process.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::UrlabBinary;

bool Has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class ValidateRunAgreeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("validate_run");
    // Every command here caches into the test's own folder, never the user's.
    env_ = "URLAB_CACHE_DIR=" + dir_ + "/cache ";
  }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  int Urlab(const std::string& args, std::string* out) {
    return RunCommand(env_ + UrlabBinary() + " " + args, out);
  }
  void WriteModels() {
    Write("arm.xml", R"(<mujoco>
  <worldbody>
    <body name="link"><joint name="hinge"/><geom size="0.1" mass="1"/>
      <camera name="eye" pos="0 0 1"/></body>
  </worldbody>
  <actuator><motor name="lift" joint="hinge"/></actuator>
</mujoco>
)");
    Write("cart.xml", R"(<mujoco>
  <worldbody>
    <body name="cart" pos="3 0 0"><joint name="slide" type="slide"/><geom size="0.1" mass="1"/>
    </body>
  </worldbody>
  <actuator><motor name="drive" joint="slide"/></actuator>
</mujoco>
)");
  }
  std::string dir_, env_;
};

TEST_F(ValidateRunAgreeTest, TheNewerKeysAreRefusedByValidateAndRunAtTheirLines) {
  WriteModels();
  struct Case {
    std::string yaml;  // after "articulations:\n  - name: a\n    mjcf: arm.xml\n"
    std::string where_what;
  };
  const Case cases[] = {
      {"    cameras: [nose]\n", ":2: a.cameras: articulation 'a' has no camera 'nose'"},
      {"cameras:\n  streams:\n    a/mouth: {rate: 5}\n",
       ":6: cameras.streams.a/mouth: articulation 'a' has no camera 'mouth'"},
      {"network: {camera_base_port: abc}\n", ":4: network.camera_base_port must be a number"},
      {"network: {camera_base_port: -1}\n", ":4: network.camera_base_port must be 1 to 65535"},
      {"network: {camera_base_port: 99999}\n", ":4: network.camera_base_port must be 1 to 65535"},
      {"    twist: {max_vx: 1}\n", ":2: a: twist needs a free base"},
      {"    input:\n      - {actuator: ghost, key: J}\n", ":5: a.input: no actuator 'ghost'"},
      {"    input:\n      - {actuator: hinge, key: J}\n", "'hinge' is a joint"},
      {"    input:\n      - {actuator: drive, key: J}\n  - {name: b, mjcf: cart.xml}\n",
       "it is an actuator of articulation 'b'"},
      {"    input:\n      - {actuator: lift, key: nokey}\n", ":5: a.input: unknown key 'nokey'"},
      {"    input:\n      - {actuator: lift, key: ''}\n", ":5: a.input: an empty key"},
      {"cameras: {width: 640.5}\n", ":4: cameras.width must be a whole number"},
      {"cameras: {samples: 1.5}\n", ":4: cameras.samples must be a whole number"},
      // sections a subsystem parses (the viewer's, registered by the tool at start)
      {"viewer: {render_scale: 3}\n", ":4: viewer.render_scale must be 0.25 to 2"},
      {"cinematic:\n  orbit_elevation: 95\n", ":5: cinematic.orbit_elevation must be -90 to 90"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string scene = Write("s" + std::to_string(i++) + ".yaml",
                                    "articulations:\n  - name: a\n    mjcf: arm.xml\n" + c.yaml);
    std::string out;
    EXPECT_EQ(Urlab("validate " + scene, &out), 1) << c.yaml << out;
    const std::string want = c.where_what.starts_with(":") ? scene + c.where_what : c.where_what;
    EXPECT_TRUE(Has(out, want)) << want << " missing in:\n" << out;
    EXPECT_FALSE(Has(out, ": OK")) << out;
    std::string run;
    EXPECT_EQ(Urlab("run --ports auto " + scene + " --duration 0.5 --no-network", &run), 1)
        << c.yaml << run;
    EXPECT_TRUE(Has(run, want)) << want << " missing in:\n" << run;
    EXPECT_FALSE(Has(run, "summary:")) << run;
  }
  // The same keys, right, pass both.
  const std::string good =
      Write("good.yaml",
            "articulations:\n  - name: a\n    mjcf: arm.xml\n    cameras: [eye]\n"
            "    input:\n      - {actuator: lift, key: Space}\n      - {actuator: lift, "
            "gamepad_axis: 1}\n"
            "  - {name: b, mjcf: cart.xml}\n"
            "cameras: {enabled: false, width: 320, samples: 0, streams: {a/eye: {rate: 5}}}\n"
            "network: {enabled: false, camera_base_port: 6000}\n"
            "viewer: {shadows: false}\ncinematic: {orbit_period: 10}\n");
  std::string out;
  EXPECT_EQ(Urlab("validate " + good, &out), 0) << out;
  EXPECT_EQ(Urlab("run --ports auto " + good + " --duration 0.3 --no-network", &out), 0) << out;
}

TEST_F(ValidateRunAgreeTest, InfinityIsRefusedLikeNaN) {
  // A sphere of infinite size and a geom at infinity compiled and validated; NaN did not.
  for (const char* attributes :
       {"size=\"nan\"", "size=\"inf\"", "size=\"1\" pos=\"0 -inf 0\"", "size=\"INF\""}) {
    const std::string model = Write("m.xml", std::string("<mujoco>\n  <worldbody>\n    <geom ") +
                                                 attributes + "/>\n  </worldbody>\n</mujoco>\n");
    std::string out;
    EXPECT_EQ(Urlab("validate " + model, &out), 1) << attributes << out;
    EXPECT_TRUE(Has(out, model + ":3:")) << attributes << out;
    EXPECT_EQ(Urlab("run --ports auto " + model + " --duration 0.3 --no-network", &out), 1)
        << attributes << out;
  }
}

TEST_F(ValidateRunAgreeTest, AMeshFileThatIsNotAFileSaysWhatItIs) {
  fs::create_directories(dir_ + "/folder.stl");
  for (const auto& [file, what] : {std::pair{std::string(dir_ + "/folder.stl"), "is a folder"},
                                   {std::string("/dev/zero"), "is a device"}}) {
    const std::string model =
        Write("m.xml", "<mujoco>\n  <asset>\n    <mesh name=\"m\" file=\"" + file +
                           "\"/>\n  </asset>\n  <worldbody><geom type=\"mesh\" "
                           "mesh=\"m\"/></worldbody>\n</mujoco>\n");
    std::string out;
    EXPECT_EQ(Urlab("validate " + model, &out), 1) << out;
    EXPECT_TRUE(Has(out, model + ":3: <mesh> file '" + file + "' " + what)) << out;
    EXPECT_FALSE(Has(out, "not found")) << out;
    EXPECT_EQ(Urlab("run --ports auto " + model + " --duration 0.3 --no-network", &out), 1) << out;
    EXPECT_TRUE(Has(out, what)) << out;
  }
}

TEST_F(ValidateRunAgreeTest, PropAndTerrainErrorsNameTheSceneLine) {
  // A binary STL of no triangles, and a PNG that is not one.
  std::string empty_stl(84, '\0');
  std::ofstream(dir_ + "/empty.stl", std::ios::binary) << empty_stl;
  Write("bad.png", "not a png");
  const std::string arm = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";
  const std::string prop = Write("p.yaml", "articulations:\n  - {name: a, mjcf: " + arm +
                                               "}\nprops:\n  - name: box\n    mesh: empty.stl\n");
  std::string out;
  EXPECT_EQ(Urlab("validate " + prop, &out), 1) << out;
  EXPECT_TRUE(Has(out, prop + ":4: box: " + dir_ + "/empty.stl")) << out;
  EXPECT_EQ(Urlab("run --ports auto " + prop + " --duration 0.3 --no-network", &out), 1) << out;
  EXPECT_TRUE(Has(out, prop + ":4: box: ")) << out;
  const std::string terrain =
      Write("t.yaml", "articulations:\n  - {name: a, mjcf: " + arm +
                          "}\nterrain:\n  - name: ground\n    png: bad.png\n"
                          "    size: [1, 1, 0.1, 0.1]\n");
  EXPECT_EQ(Urlab("validate " + terrain, &out), 1) << out;
  // The PNG is checked when the terrain is built: the scene entry's line, the file, the reason
  // (MuJoCo's message on the generated element used to be the first thing said).
  EXPECT_TRUE(Has(out, terrain + ":4: ground: " + dir_ + "/bad.png: not a PNG")) << out;
}

TEST_F(ValidateRunAgreeTest, ValidateWritesNothingNotEvenIntoTheCache) {
  // An OBJ prop (converted and decomposed: both cached by a build) and a PLY mesh in the MJCF
  // (converted to OBJ in the cache by a build).
  Write("cube.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
        "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\n"
        "f 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
  Write("tet.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  Write("tet.xml",
        "<mujoco>\n  <asset><mesh name=\"tet\" file=\"tet.ply\"/></asset>\n"
        "  <worldbody><body pos=\"0 0 1\"><freejoint/><geom type=\"mesh\" mesh=\"tet\"/></body>"
        "</worldbody>\n</mujoco>\n");
  const std::string scene =
      Write("s.yaml",
            "articulations:\n  - {name: t, mjcf: tet.xml}\nprops:\n  - {name: cube, "
            "mesh: cube.obj, pos: [2, 0, 0.5]}\n");
  std::string out;
  ASSERT_EQ(Urlab("validate " + scene, &out), 0) << out;
  EXPECT_FALSE(fs::exists(dir_ + "/cache")) << out;
  // A run does use the cache (so the check above could fail).
  ASSERT_EQ(Urlab("run --ports auto " + scene + " --duration 0.3 --no-network", &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir_ + "/cache")) << out;
}

TEST_F(ValidateRunAgreeTest, ValidateOfAnEngineErrorNamesTheFileAndGivesTheHint) {
  // MuJoCo's compiler runs the model in its tiny memory and reports "engine error: ... stack
  // overflow" without a line; validate used to print it without file or hint.
  const std::string model = Write("tiny.xml", R"(<mujoco>
  <size memory="100"/>
  <worldbody>
    <body><freejoint/><geom size="0.1"/></body>
    <body pos="1 0 0"><freejoint/><geom size="0.1"/></body>
  </worldbody>
</mujoco>
)");
  std::string run, out;
  const int run_code = Urlab("run --ports auto " + model + " --duration 0.3 --no-network", &run);
  EXPECT_EQ(Urlab("validate " + model, &out), 1) << out;
  EXPECT_TRUE(Has(out, "error: " + model + ": ")) << out;
  EXPECT_TRUE(Has(out, "stack overflow")) << out;
  EXPECT_TRUE(Has(out, "hint: ")) << out;
  EXPECT_EQ(run_code, 1) << run;
  EXPECT_TRUE(Has(run, "hint: ")) << run;
}

TEST_F(ValidateRunAgreeTest, ADivergedRunStopsWithExit1AsTheHelpSays) {
  const std::string model = Write("div.xml", R"(<mujoco>
  <option timestep="0.05"/>
  <worldbody>
    <body pos="0 0 1"><joint type="hinge" stiffness="1e9" springref="1"/>
      <geom type="capsule" size="0.1" fromto="0 0 0 0.3 0 0"/></body>
  </worldbody>
</mujoco>
)");
  std::string out;
  EXPECT_EQ(Urlab("run --ports auto " + model + " --max-speed --duration 5 --no-network", &out), 1)
      << out;
  EXPECT_TRUE(Has(out, "urlab: error: " + model + ": at t=")) << out;
  EXPECT_TRUE(Has(out, "simulation diverged")) << out;
  EXPECT_TRUE(Has(out, "(stopped: the simulation diverged)")) << out;
  EXPECT_TRUE(Has(out, "--reset-on-divergence")) << out;
  // With auto-reset it goes on to --duration and exits 0.
  EXPECT_EQ(Urlab("--log-level error run --ports auto " + model +
                      " --max-speed --duration 0.5 --no-network --reset-on-divergence",
                  &out),
            0)
      << out;
  // The help says what happens.
  EXPECT_EQ(Urlab("run --help", &out), 0);
  EXPECT_TRUE(Has(out, "divergence stops it")) << out;
}

TEST_F(ValidateRunAgreeTest, APacedRunThatCannotKeepUpSaysSoOnce) {
  // A microsecond timestep: no machine steps this arm a million times a wall second.
  const std::string arm = URLAB_SOURCE_DIR "/examples/models/servo_arm.xml";
  const std::string scene = Write(
      "slow.yaml", "articulations:\n  - {name: a, mjcf: " + arm + "}\noptions: {timestep: 1e-6}\n");
  std::string out;
  // Six wall-clock seconds (--duration counts simulated time, which this run hardly makes).
  EXPECT_EQ(RunCommand(env_ + "timeout --preserve-status -s INT 6 " + UrlabBinary() +
                           " run --ports auto " + scene + " --no-network --no-cameras",
                       &out),
            130)
      << out;
  // Once (3 s behind), not once a second: the next reminder would come 30 s later.
  EXPECT_EQ(Count(out, "cannot keep up"), 1) << out;
  // As fast as possible is never "behind".
  EXPECT_EQ(RunCommand(env_ + "timeout --preserve-status -s INT 4 " + UrlabBinary() +
                           " run --ports auto " + scene + " --max-speed --no-network",
                       &out),
            130)
      << out;
  EXPECT_EQ(Count(out, "cannot keep up"), 0) << out;
}

}  // namespace
}  // namespace urlab
