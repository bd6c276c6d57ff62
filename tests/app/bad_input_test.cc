// Bad input never runs wrong and the CLI tells the truth: the real binary on bad files, bad
// numbers, outputs aimed at inputs, signals and MuJoCo errors.
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "mujoco_test.h"
#include "process.h"

namespace urlab {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::SourcePath;
using testing::UrlabBinary;

const std::string kArm = URLAB_SOURCE_DIR "/examples/models/pendulum_arm.xml";

bool Has(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

using Process = testing::UrlabProcess;

class CliBadInputTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("cli_bad"); }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  int Urlab(const std::string& args, std::string* out) {
    return RunCommand(UrlabBinary() + " " + args, out);
  }
  std::string dir_;
};

TEST_F(CliBadInputTest, ValidateRunsEveryBeginPlayCheckAndRunAgrees) {
  const std::string scene = Write("s.yaml",
                                  "articulations:\n"
                                  "  - name: a\n    mjcf: " +
                                      kArm +
                                      "\n"
                                      "    hold_keyframe: true\n"
                                      "    controller: {type: pd, gains: {wrist: {kp: 1}}}\n"
                                      "  - name: a_b\n    mjcf: " +
                                      kArm +
                                      "\n"
                                      "    keyframe: nowhere\n");
  std::string out;
  EXPECT_EQ(Urlab("validate " + scene, &out), 1) << out;
  for (const std::string& want : std::vector<std::string>{
           scene + ":6: articulation names 'a' and 'a_b' overlap",
           scene + ":2: a: hold_keyframe needs an initial 'keyframe'", "2 problem(s)"}) {
    EXPECT_TRUE(Has(out, want)) << want << " missing in:\n" << out;
  }
  std::string run_out, compile_out;
  EXPECT_EQ(Urlab("run --ports auto " + scene + " --duration 0.2", &run_out), 1) << run_out;
  EXPECT_TRUE(Has(run_out, "overlap")) << run_out;
  EXPECT_TRUE(Has(run_out, "(and 1 more problem(s))")) << run_out;
  EXPECT_FALSE(Has(run_out, "playing")) << run_out;
  EXPECT_EQ(Urlab("compile " + scene, &compile_out), 1) << compile_out;
  // With the names fixed, the checks against the compiled model speak (both at once).
  Write("s2.yaml",
        "articulations:\n"
        "  - name: a\n    mjcf: " +
            kArm +
            "\n"
            "    controller: {type: pd, gains: {wrist: {kp: 1}}}\n"
            "  - name: b\n    mjcf: " +
            kArm +
            "\n"
            "    keyframe: nowhere\n");
  EXPECT_EQ(Urlab("validate " + dir_ + "/s2.yaml", &out), 1) << out;
  EXPECT_TRUE(Has(out, "s2.yaml:4: a: controller gains: no actuated joint or actuator 'wrist'"))
      << out;
  EXPECT_TRUE(Has(out, "s2.yaml:5: b: keyframe 'nowhere' is not in")) << out;
  EXPECT_EQ(Urlab("run --ports auto " + dir_ + "/s2.yaml --duration 0.2", &run_out), 1) << run_out;
  EXPECT_TRUE(Has(run_out, "'wrist'")) << run_out;
}

TEST_F(CliBadInputTest, ASingleFileTakesTheScenePathInEveryCommand) {
  // A keyframe longer than the model: MuJoCo refuses it (without a line, when it attaches the
  // articulation); validate, compile, run and bench all refuse it at its line.
  const std::string model = Write("two.xml", R"(<mujoco>
  <worldbody>
    <body><joint name="j1"/><geom size="0.1"/>
      <body pos="0 0 1"><joint name="j2"/><geom size="0.1"/></body></body>
  </worldbody>
  <keyframe><key name="long" qpos="0.5 0.1 0.2"/></keyframe>
</mujoco>
)");
  for (const char* cmd : {"validate", "compile", "run", "bench loop"}) {
    std::string out;
    EXPECT_EQ(
        Urlab(std::string(cmd) + " " + model + (std::string(cmd) == "run" ? " --duration 1" : ""),
              &out),
        1)
        << cmd << ": " << out;
    EXPECT_TRUE(Has(out, "two.xml:6: two: keyframe 'long': qpos has 3 value(s)")) << cmd << out;
  }
}

TEST_F(CliBadInputTest, ShortFromToUnderAPlacementIsAnErrorNotGarbageGeometry) {
  Write("stick.xml",
        "<mujoco>\n  <worldbody>\n    <body>\n      <freejoint/>\n"
        "      <geom type=\"capsule\" size=\"0.05\" fromto=\"0 0 0 0 0\"/>\n"
        "    </body>\n  </worldbody>\n</mujoco>\n");
  const std::string scene =
      Write("s.yaml", "articulations:\n  - {name: s, mjcf: stick.xml, pos: [0, 0, 1]}\n");
  std::string out;
  EXPECT_EQ(Urlab("run --ports auto " + scene + " --duration 0.3", &out), 1) << out;
  EXPECT_TRUE(Has(out, dir_ + "/stick.xml:5:")) << out;
  EXPECT_TRUE(Has(out, "'fromto' does not have enough data")) << out;
  EXPECT_EQ(Urlab("validate " + scene, &out), 1) << out;
}

TEST_F(CliBadInputTest, ValidateWritesNothing) {
  const std::string scene =
      Write("s.yaml", "articulations:\n  - {name: a, mjcf: " + kArm + "}\nsave_debug_xml: dbg\n");
  std::string out;
  EXPECT_EQ(Urlab("validate " + scene, &out), 0) << out;
  EXPECT_FALSE(fs::exists(dir_ + "/dbg")) << out;
}

TEST_F(CliBadInputTest, NumbersOnTheCommandLineAreChecked) {
  std::string out;
  const std::string run = "run --ports auto " + kArm;
  EXPECT_NE(Urlab(run + " --duration nan", &out), 0);
  EXPECT_TRUE(Has(out, "--duration: must be a finite number > 0, not nan")) << out;
  EXPECT_NE(Urlab(run + " --duration inf", &out), 0);
  EXPECT_NE(Urlab(run + " --duration -1", &out), 0);
  EXPECT_NE(Urlab(run + " --duration 1x", &out), 0);
  EXPECT_NE(Urlab(run + " --speed 50.5 --duration 0.1", &out), 0);
  EXPECT_TRUE(Has(out, "--speed: '50.5' is not an integer")) << out;
  EXPECT_FALSE(Has(out, "summary")) << out;
  EXPECT_EQ(Urlab(run + " --speed 50 --duration 0.1", &out), 0) << out;
}

TEST_F(CliBadInputTest, OutputsNeverOverwriteAnInput) {
  const std::string text =
      "<mujoco>\n  <!-- comments the round trip would drop -->\n"
      "  <include file=\"parts/body.xml\"/>\n</mujoco>\n";
  const std::string model = Write("a.xml", text);
  const std::string part = Write("parts/body.xml",
                                 "<mujoco><worldbody><geom size=\"1\"/>"
                                 "</worldbody></mujoco>\n");
  const std::string part_text = testing::ReadTextFile(part);
  fs::create_symlink(model, dir_ + "/link.xml");
  std::string out;
  for (const std::string& target :
       std::vector<std::string>{model, dir_ + "/./a.xml", dir_ + "/link.xml", part}) {
    EXPECT_EQ(Urlab("mjcf roundtrip " + model + " -o " + target, &out), 1) << target << out;
    EXPECT_TRUE(Has(out, "would overwrite")) << out;
  }
  EXPECT_EQ(Urlab("compile " + model + " --save-xml " + part, &out), 1) << out;
  EXPECT_EQ(Urlab("compile " + model + " --save-mjb " + model, &out), 1) << out;
  EXPECT_TRUE(Has(out, "--save-mjb would overwrite")) << out;
  EXPECT_EQ(testing::ReadTextFile(model), text);
  EXPECT_EQ(testing::ReadTextFile(part), part_text);
  // Missing folders are created for every output.
  EXPECT_EQ(Urlab("mjcf roundtrip " + model + " -o " + dir_ + "/new/deep/rt.xml", &out), 0) << out;
  EXPECT_EQ(Urlab("compile " + model + " --save-xml " + dir_ + "/x/y/m.xml --save-mjb " + dir_ +
                      "/z/m.mjb",
                  &out),
            0)
      << out;
  EXPECT_TRUE(fs::exists(dir_ + "/new/deep/rt.xml"));
  EXPECT_TRUE(fs::exists(dir_ + "/x/y/m.xml"));
  EXPECT_TRUE(fs::exists(dir_ + "/z/m.mjb"));
}

TEST_F(CliBadInputTest, PathsThatAreNotRegularFilesAreRefused) {
  const std::string fifo = dir_ + "/pipe.xml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string out;
  // `timeout` guards against a FIFO open blocking forever.
  EXPECT_EQ(RunCommand("timeout 10 " + UrlabBinary() + " compile " + fifo, &out), 1) << out;
  EXPECT_TRUE(Has(out, "is a FIFO (named pipe), not a regular file")) << out;
  EXPECT_EQ(Urlab("validate /dev/zero", &out), 1) << out;
  EXPECT_TRUE(Has(out, "is a device")) << out;
  EXPECT_EQ(Urlab("run /dev/zero --duration 0.1", &out), 1) << out;
  EXPECT_EQ(Urlab("mjcf roundtrip " + dir_ + " -o " + dir_ + "/o.xml", &out), 1) << out;
  EXPECT_TRUE(Has(out, "is a folder")) << out;
  const std::string scene = Write("s.yaml", "articulations:\n  - {name: a, mjcf: /dev/zero}\n");
  EXPECT_EQ(Urlab("validate " + scene, &out), 1) << out;
  EXPECT_TRUE(Has(out, scene + ":2:")) << out;
  const std::string big = dir_ + "/big.xml";
  std::ofstream(big) << "<mujoco/>";
  fs::resize_file(big, (64u << 20) + 1);
  EXPECT_EQ(Urlab("compile " + big, &out), 1) << out;
  EXPECT_TRUE(Has(out, "larger than the 64 MiB")) << out;
}

TEST_F(CliBadInputTest, ErrorsAlwaysHaveALocation) {
  // yaml-cpp conversions the parser did not expect used to end as "unexpected error".
  const std::string scene =
      Write("s.yaml", "articulations:\n  - {name: a, mjcf: " + kArm + "}\n[1, 2]: x\n");
  std::string out;
  EXPECT_EQ(Urlab("run --ports auto " + scene, &out), 1) << out;
  EXPECT_TRUE(Has(out, "urlab: error: " + scene + ":3: keys in the scene must be names")) << out;
  EXPECT_FALSE(Has(out, "unexpected")) << out;
  const std::string future = Write(
      "f.yaml", "articulations:\n  - {name: a, mjcf: " + kArm + "}\nlights: [{pos: [0, 0, 3]}]\n");
  EXPECT_EQ(Urlab("validate " + future, &out), 1) << out;
  EXPECT_TRUE(Has(out, future + ":3: 'lights:' is not a scene section")) << out;
}

TEST_F(CliBadInputTest, SignalsDuringALongCompileStopAtOnce) {
  // A mesh of 160,000 vertices takes seconds to load and compile on the main thread (its convex
  // hull, its inertia).
  std::string obj;
  constexpr int kRings = 400;
  for (int i = 0; i < kRings; ++i) {
    for (int j = 0; j < kRings; ++j) {
      const double th = M_PI * (i + 0.5) / kRings, ph = 2 * M_PI * j / kRings;
      obj += "v " + std::to_string(std::sin(th) * std::cos(ph)) + " " +
             std::to_string(std::sin(th) * std::sin(ph)) + " " + std::to_string(std::cos(th)) +
             "\n";
    }
  }
  for (int i = 0; i + 1 < kRings; ++i) {
    for (int j = 0; j < kRings; ++j) {
      const int a = i * kRings + j + 1, b = i * kRings + (j + 1) % kRings + 1;
      obj += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(b + kRings) +
             "\nf " + std::to_string(a) + " " + std::to_string(b + kRings) + " " +
             std::to_string(a + kRings) + "\n";
    }
  }
  Write("ball.obj", obj);
  const std::string model = Write("slow.xml", R"(<mujoco>
  <asset><mesh name="ball" file="ball.obj"/></asset>
  <worldbody><body><freejoint/><geom type="mesh" mesh="ball"/></body></worldbody>
</mujoco>
)");
  for (const auto& [sig, code] : {std::pair{SIGINT, 130}, {SIGTERM, 143}, {SIGHUP, 129}}) {
    Process p("validate " + model, dir_ + "/v" + std::to_string(sig) + ".txt");
    // Signalled inside the compile: its handler is in place and it has worked a while (processor
    // time, whatever the machine's load; the compile takes seconds of it).
    ASSERT_TRUE(p.WaitForHandler(sig)) << p.output();
    ASSERT_TRUE(p.WaitForCpu(std::chrono::milliseconds(300))) << p.output();
    p.Signal(sig);
    // Stopped inside the compile: it never reports the model OK (the bound only ends a hang).
    EXPECT_EQ(p.Wait(std::chrono::seconds(60)), code) << p.output();
    EXPECT_TRUE(Has(p.output(), "interrupted by SIG")) << p.output();
    EXPECT_FALSE(Has(p.output(), ": OK")) << p.output();
  }
}

TEST_F(CliBadInputTest, AnInterruptedRunExitsWith128PlusTheSignal) {
  for (const auto& [sig, code, name] :
       {std::tuple{SIGINT, 130, "SIGINT"}, {SIGHUP, 129, "SIGHUP"}}) {
    Process p("run --ports auto " + SourcePath("examples/scenes/two_arms.yaml"),
              dir_ + "/r" + std::to_string(sig) + ".txt");
    ASSERT_TRUE(p.WaitFor("playing")) << p.output();
    p.Signal(sig);
    EXPECT_EQ(p.Wait(std::chrono::seconds(60)), code) << p.output();
    EXPECT_TRUE(Has(p.output(), std::string("(stopped by signal ") + name + ")")) << p.output();
  }
  // A run that reaches --duration is a finished run.
  std::string out;
  EXPECT_EQ(Urlab("run --ports auto " + kArm + " --duration 0.2", &out), 0) << out;
}

TEST_F(CliBadInputTest, APausedRunSaysHowToResumeAndSigusr1Resumes) {
  Process p("run --ports auto " + kArm + " --paused --max-speed", dir_ + "/p.txt");
  ASSERT_TRUE(p.WaitFor("paused: send SIGUSR1 to resume")) << p.output();
  p.Signal(SIGUSR1);
  ASSERT_TRUE(p.WaitFor("resumed by SIGUSR1")) << p.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // steps at --max-speed
  p.Signal(SIGINT);
  EXPECT_EQ(p.Wait(std::chrono::seconds(60)), 130) << p.output();
  EXPECT_FALSE(Has(p.output(), "steps=0 ")) << p.output();
}

TEST_F(CliBadInputTest, AMujocoErrorStopsTheRunWithItsMessageAndAHint) {
  // Boxes falling onto a floor: fine until the contacts outgrow a tiny memory.
  std::string bodies;
  for (int i = 0; i < 20; ++i) {
    bodies += "    <body pos=\"" + std::to_string((i % 5) * 0.3) + " " +
              std::to_string((i / 5) * 0.3) + " " + std::to_string(0.3 + 0.25 * i) +
              "\"><freejoint/><geom type=\"box\" size=\"0.1 0.1 0.1\"/></body>\n";
  }
  const std::string model = Write("boxes.xml",
                                  "<mujoco>\n  <size memory=\"30K\"/>\n"
                                  "  <worldbody>\n"
                                  "    <geom type=\"plane\" size=\"5 5 0.1\"/>\n" +
                                      bodies + "  </worldbody>\n</mujoco>\n");
  std::string out;
  EXPECT_EQ(Urlab("run --ports auto " + model + " --max-speed --duration 5", &out), 1) << out;
  EXPECT_TRUE(Has(out, "urlab: error: " + model + ": at t=")) << out;
  EXPECT_TRUE(Has(out, "stack overflow")) << out;
  EXPECT_TRUE(Has(out, "hint: ")) << out;
  EXPECT_TRUE(Has(out, "size: {memory:")) << out;
  EXPECT_TRUE(Has(out, "(stopped by a MuJoCo error)")) << out;
  // With auto-reset it goes on until --duration and finishes normally.
  EXPECT_EQ(Urlab("--log-level warn run --ports auto " + model +
                      " --max-speed --duration 0.5 "
                      "--reset-on-divergence",
                  &out),
            0)
      << out;
}

TEST_F(CliBadInputTest, RepeatedMujocoWarningsAreRateLimited) {
  // Diverges at once and is reset every step: MuJoCo warns after every reset.
  const std::string model = Write("div.xml", R"(<mujoco>
  <option timestep="0.05"/>
  <worldbody>
    <body pos="0 0 1"><joint type="hinge" stiffness="1e9" springref="1"/>
      <geom type="capsule" size="0.1" fromto="0 0 0 0.3 0 0"/></body>
  </worldbody>
</mujoco>
)");
  std::string out;
  // Two wall-clock seconds (--duration counts simulated time: 40 steps here).
  ASSERT_EQ(RunCommand("timeout -s INT 2 " + UrlabBinary() + " run --ports auto " + model +
                           " --max-speed --reset-on-divergence 2>&1 | grep -c 'MuJoCo:'",
                       &out),
            0)
      << out;
  // Thousands of warnings in 2 s; at most one line a second, plus the first and the count.
  EXPECT_LE(std::stoi(out), 5) << out;
}

}  // namespace
}  // namespace urlab
