// The Manager: BeginPlay/Tick/EndPlay on real scenes, one manager per process, per-articulation
// initial keyframes, holds and PD control, divergence and MuJoCo error reports, host-driven
// mocap bodies, and a thread storming commands while the manager ticks (run under TSan).
#include "urlab/world/manager.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "mujoco_test.h"
#include "urlab/control/controllers.h"
#include "wait.h"

namespace urlab {
namespace {

using Clock = std::chrono::steady_clock;
using physics::EngineEvent;
using physics::EngineEventKind;
using testing::WaitFor;
using world::Manager;
using world::ManagerOptions;

// One hinged link driven by a strong motor, and a mocap marker.
constexpr const char* kArmXml = R"(<mujoco model="arm">
  <compiler autolimits="true"/>
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.1" armature="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
    </body>
    <body name="marker" mocap="true" pos="0 0 2">
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="hinge_motor" joint="hinge" ctrlrange="-100 100"/>
  </actuator>
  <keyframe>
    <key name="up" qpos="0.7"/>
    <key name="down" qpos="-0.4"/>
  </keyframe>
</mujoco>
)";

class ManagerTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("manager");
    arm_ = Write("arm.xml", kArmXml);
  }
  std::string Write(const std::string& rel, const std::string& text) {
    return testing::WriteTextFile(dir_, rel, text);
  }
  world::SceneConfig Scene(const std::string& yaml) {
    return world::ParseScene(yaml, dir_ + "/scene.yaml");
  }
  // Two arms; `a_extra` / `b_extra` are appended to each articulation's mapping.
  world::SceneConfig TwoArms(const std::string& a_extra, const std::string& b_extra,
                             const std::string& scene_extra = "") {
    return Scene("articulations:\n  - name: a\n    mjcf: arm.xml\n    pos: [0, -1, 0]\n" + a_extra +
                 "  - name: b\n    mjcf: arm.xml\n    pos: [0, 1, 0]\n" + b_extra + scene_extra);
  }
  static ManagerOptions Fast(bool paused = false) {
    ManagerOptions o;
    o.as_fast_as_possible = true;
    o.start_paused = paused;
    return o;
  }
  // Ticks until `steps` more physics steps were taken (fails after 30 s).
  static void TickSteps(Manager& m, std::uint64_t steps) {
    const std::uint64_t target = m.session().engine().step_count() + steps;
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (m.session().engine().step_count() < target) {
      m.Tick();
      ASSERT_LT(Clock::now(), deadline) << "the physics thread did not advance";
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    m.Tick();
  }
  // Ticks until `pred` holds (fails after 30 s).
  template <typename Pred>
  static void TickUntil(Manager& m, Pred pred) {
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (!pred()) {
      m.Tick();
      ASSERT_LT(Clock::now(), deadline) << "condition not reached";
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  static double Qpos(Manager& m, const std::string& joint) {
    const physics::PhysicsState s = m.session().engine().Snapshot();
    const int j = mj_name2id(m.session().engine().model(), mjOBJ_JOINT, joint.c_str());
    EXPECT_GE(j, 0) << joint;
    return s.qpos[static_cast<std::size_t>(m.session().engine().model()->jnt_qposadr[j])];
  }
  static double Qvel(Manager& m, const std::string& joint) {
    const physics::PhysicsState s = m.session().engine().Snapshot();
    const int j = mj_name2id(m.session().engine().model(), mjOBJ_JOINT, joint.c_str());
    EXPECT_GE(j, 0) << joint;
    return s.qvel[static_cast<std::size_t>(m.session().engine().model()->jnt_dofadr[j])];
  }

  std::string dir_;
  std::string arm_;
};

TEST_F(ManagerTest, BeginPlayTickEndPlay) {
  Manager m(Fast());
  EXPECT_FALSE(m.playing());
  EXPECT_EQ(m.Tick(), 0);  // not playing: nothing happens
  m.BeginPlay(TwoArms("", ""));
  ASSERT_TRUE(m.playing());
  EXPECT_TRUE(m.session().engine().running());
  ASSERT_EQ(m.session().articulations().size(), 2u);
  EXPECT_EQ(m.session().articulations()[0].prefix, "a_");
  EXPECT_EQ(m.session().articulations()[1].name(), "b");
  EXPECT_EQ(m.session().articulations()[1].control->num_actuators(), 1);
  EXPECT_EQ(m.session().OwnerOf("b_hinge"), &m.session().articulations()[1]);
  EXPECT_EQ(m.session().OwnerOf("hinge"), nullptr);
  TickSteps(m, 200);
  ASSERT_NE(m.frame(), nullptr);
  EXPECT_GT(m.frame()->step, 0u);
  const auto pose = m.BodyPose("b", "link");
  ASSERT_TRUE(pose);
  EXPECT_NEAR(pose->pos[1], 1.0, 1e-9);  // placed at y = 1
  m.EndPlay();
  EXPECT_FALSE(m.playing());
  EXPECT_EQ(m.frame(), nullptr);
  EXPECT_THROW(m.session().engine(), Error);
  m.EndPlay();  // idempotent
  // The same manager can play again.
  m.BeginPlay(TwoArms("", ""));
  TickSteps(m, 10);
}

TEST_F(ManagerTest, SeveralManagersPlayInOneProcess) {
  // A training and an evaluation world side by side: each steps its own simulation.
  Manager first(Fast()), second(Fast());
  first.BeginPlay(TwoArms("", ""));
  second.BeginPlay(TwoArms("", ""));
  EXPECT_TRUE(first.playing());
  EXPECT_TRUE(second.playing());
  EXPECT_NE(&first.session().engine(), &second.session().engine());
  EXPECT_THROW(first.BeginPlay(TwoArms("", "")), Error);  // already playing
  TickSteps(first, 10);
  TickSteps(second, 10);
  first.EndPlay();
  EXPECT_TRUE(second.session().engine().running());  // ending one leaves the other playing
  TickSteps(second, 10);
  first.BeginPlay(TwoArms("", ""));
  EXPECT_TRUE(first.playing());
}

TEST_F(ManagerTest, DestructorEndsPlay) {
  {
    Manager m(Fast());
    m.BeginPlay(TwoArms("", ""));
    TickSteps(m, 10);
  }
  Manager again(Fast());
  again.BeginPlay(TwoArms("", ""));
  EXPECT_TRUE(again.playing());
}

TEST_F(ManagerTest, BadSceneThrowsWithFileLineAndLeavesNothingPlaying) {
  Manager m(Fast());
  const world::SceneConfig bad = TwoArms("",
                                         "    controller:\n      type: pd\n      gains:\n"
                                         "        elbow: {kp: 5}\n");
  try {
    m.BeginPlay(bad);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.yaml:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'elbow'"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(m.playing());
  // Overlapping articulation names are refused (prefix "a_" would own "a_b_...").
  EXPECT_THROW(m.BeginPlay(Scene("articulations:\n  - {name: a, mjcf: arm.xml}\n"
                                 "  - {name: a_b, mjcf: arm.xml, pos: [0, 2, 0]}\n")),
               InputError);
  EXPECT_THROW(m.BeginPlay(TwoArms("    hold_keyframe: true\n", "")), InputError);
  Manager other(Fast());
  other.BeginPlay(TwoArms("", ""));  // the failed BeginPlays released the world
  EXPECT_TRUE(other.playing());
}

TEST_F(ManagerTest, InitialKeyframeAppliesOnlyToItsArticulation) {
  Manager m(Fast(/*paused=*/true));
  m.BeginPlay(TwoArms("    keyframe: up\n", "    keyframe: down\n", ""));
  EXPECT_DOUBLE_EQ(Qpos(m, "a_hinge"), 0.7);
  EXPECT_DOUBLE_EQ(Qpos(m, "b_hinge"), -0.4);
  EXPECT_EQ(m.session().articulations()[0].initial_key,
            mj_name2id(m.session().engine().model(), mjOBJ_KEY, "a_up"));

  // A per-articulation reset leaves the other one untouched.
  m.session().ResetArticulation("b", "up");
  TickUntil(m, [&] { return Qpos(m, "b_hinge") == 0.7; });
  EXPECT_DOUBLE_EQ(Qpos(m, "a_hinge"), 0.7);
  m.session().ResetArticulation("a", "down");
  TickUntil(m, [&] { return Qpos(m, "a_hinge") == -0.4; });
  EXPECT_DOUBLE_EQ(Qpos(m, "b_hinge"), 0.7);
  // Back to the initial keyframes.
  m.session().ResetToInitialState();
  TickUntil(m, [&] { return Qpos(m, "b_hinge") == -0.4 && Qpos(m, "a_hinge") == 0.7; });
  EXPECT_THROW(m.session().ResetArticulation("c"), Error);
  EXPECT_THROW(m.session().ResetArticulation("a", "nope"), Error);

  // An articulation without an initial keyframe starts at its reference configuration.
  m.EndPlay();
  m.BeginPlay(TwoArms("    keyframe: up\n", ""));
  EXPECT_DOUBLE_EQ(Qpos(m, "a_hinge"), 0.7);
  EXPECT_DOUBLE_EQ(Qpos(m, "b_hinge"), 0.0);
  EXPECT_THROW(m.session().ResetArticulation("b"), Error);  // no initial keyframe to go back to
}

TEST_F(ManagerTest, HoldKeyframeKeepsThePose) {
  Manager m(Fast());
  const std::string pd = "    controller: {type: pd, kp: 1000, kv: 50}\n";
  m.BeginPlay(TwoArms(pd + "    keyframe: up\n    hold_keyframe: true\n",
                      pd + "    keyframe: up\n"));  // b: PD towards its own source's targets
  EXPECT_TRUE(m.session().articulations()[0].control->holding());
  EXPECT_FALSE(m.session().articulations()[1].control->holding());
  TickSteps(m, 1500);                          // 3 s
  EXPECT_NEAR(Qpos(m, "a_hinge"), 0.7, 5e-3);  // gravity sag of a PD servo: ~1.4 Nm / kp
  EXPECT_NEAR(Qvel(m, "a_hinge"), 0.0, 1e-3);
  // b's sources start at its initial pose (nothing sent yet: it keeps it, not chasing zeros).
  EXPECT_NEAR(Qpos(m, "b_hinge"), 0.7, 5e-3);
  // A target sent to b moves it; a, holding its keyframe, ignores one sent to it.
  const auto& arts = m.session().articulations();
  for (const auto& art : arts) {
    ASSERT_TRUE(art.control->SetTarget(m.session().controls().global_source(), 0, 0.0));
  }
  TickSteps(m, 1500);
  EXPECT_NEAR(Qpos(m, "b_hinge"), 0.0, 5e-3);
  EXPECT_NEAR(Qpos(m, "a_hinge"), 0.7, 5e-3);
}

TEST_F(ManagerTest, PdHeldJointSettlesAtItsTarget) {
  Manager m(Fast());
  m.BeginPlay(
      TwoArms("    controller:\n      type: pd\n      kp: 50\n      gains:\n"
              "        hinge: {kp: 2000, kv: 60}\n",
              "", "control_source: ui\n"));
  auto& pd =
      dynamic_cast<control::PdController&>(*m.session().articulations()[0].control->controller());
  EXPECT_DOUBLE_EQ(pd.gains(0).kp, 2000);  // per-joint gains over the defaults
  EXPECT_DOUBLE_EQ(pd.gains(0).kv, 60);
  EXPECT_EQ(m.session().controls().global_source(), control::ControlSource::kUi);
  ASSERT_TRUE(m.session().articulations()[0].control->SetTarget(control::ControlSource::kUi,
                                                                "hinge_motor", -0.3));
  TickSteps(m, 2000);
  EXPECT_NEAR(Qpos(m, "a_hinge"), -0.3, 2e-3);
  EXPECT_NEAR(Qvel(m, "a_hinge"), 0.0, 1e-3);
}

TEST_F(ManagerTest, ControlSourceGlobalAndOverride) {
  Manager m(Fast(/*paused=*/true));
  m.BeginPlay(TwoArms("", "    control_source: network\n", "control_source: ui\n"));
  auto* a = m.session().articulations()[0].control;
  auto* b = m.session().articulations()[1].control;
  EXPECT_EQ(a->EffectiveSource(m.session().controls().global_source()),
            control::ControlSource::kUi);
  EXPECT_EQ(b->EffectiveSource(m.session().controls().global_source()),
            control::ControlSource::kNetwork);
  for (auto* c : {a, b}) {
    c->SetTarget(control::ControlSource::kUi, 0, 1.5);
    c->SetTarget(control::ControlSource::kNetwork, 0, -2.5);
  }
  m.session().engine().StepSync(1);  // passthrough: the active source's target lands in d->ctrl
  const physics::PhysicsState s = m.session().engine().Snapshot();
  EXPECT_DOUBLE_EQ(s.ctrl[static_cast<std::size_t>(a->actuator_ids()[0])], 1.5);
  EXPECT_DOUBLE_EQ(s.ctrl[static_cast<std::size_t>(b->actuator_ids()[0])], -2.5);
}

TEST_F(ManagerTest, KeyframeControllerFromTheScene) {
  Manager m(Fast(/*paused=*/true));  // stepped with StepSync: the sequence loops quickly
  m.BeginPlay(TwoArms(
      "    controller:\n      type: keyframe\n      kp: 2000\n      kv: 60\n      loop: true\n"
      "      sequence:\n        - {keyframe: up, blend: 0.2, hold: 0.3}\n"
      "        - {keyframe: down, blend: 0.2, hold: 0.3}\n",
      ""));
  auto& kf = dynamic_cast<control::KeyframeController&>(
      *m.session().articulations()[0].control->controller());
  ASSERT_EQ(kf.poses().size(), 2u);
  EXPECT_DOUBLE_EQ(kf.poses()[1].positions[0], -0.4);
  for (int i = 0; i < 2000 && !(kf.current_pose() == 1 && !kf.blending()); ++i) {
    m.session().engine().StepSync(1);
  }
  ASSERT_EQ(kf.current_pose(), 1);
  m.session().engine().StepSync(100);  // 0.2 s into holding "down" (0.3 s)
  m.Tick();
  EXPECT_NEAR(Qpos(m, "a_hinge"), -0.4, 0.02);
  EXPECT_THROW(
      {
        Manager other(Fast());
        m.EndPlay();
        other.BeginPlay(
            TwoArms("    controller:\n      type: keyframe\n      sequence:\n"
                    "        - {keyframe: sideways}\n",
                    ""));
      },
      InputError);
}

TEST_F(ManagerTest, DivergenceIsReportedWithArticulationAndJoint) {
  ExpectWarning("The simulation is unstable");
  ManagerOptions o = Fast();
  o.reset_on_divergence = true;
  std::vector<EngineEvent> events;  // outlives the manager, whose EndPlay delivers events
  Manager m(o);
  // b: an absurdly stiff joint spring, integrated explicitly, blows up within a few steps.
  std::string unstable = kArmXml;
  unstable.replace(unstable.find("damping=\"0.1\""), 13, "stiffness=\"1e9\"");
  Write("unstable.xml", unstable);
  m.BeginPlay(
      Scene("articulations:\n  - {name: a, mjcf: arm.xml, pos: [0, -1, 0], keyframe: up}\n"
            "  - {name: b, mjcf: unstable.xml, pos: [0, 1, 0], keyframe: up}\n"));
  m.AddEventListener([&](const EngineEvent& e) { events.push_back(e); });
  TickUntil(m, [&] {
    int divergences = 0, resets = 0;
    for (const auto& e : events) {
      divergences += e.kind == EngineEventKind::kDivergence;
      resets += e.kind == EngineEventKind::kReset && e.message == "reset to the initial state";
    }
    return divergences > 0 && resets > 0;
  });
  const auto it = std::find_if(events.begin(), events.end(), [](const EngineEvent& e) {
    return e.kind == EngineEventKind::kDivergence;
  });
  ASSERT_NE(it, events.end());
  EXPECT_EQ(it->articulation, "b");
  EXPECT_EQ(it->joint_name, "b_hinge");
  EXPECT_TRUE(it->auto_reset);
  EXPECT_TRUE(m.session().engine().running());
  m.session().SetResetOnDivergence(false);
}

TEST_F(ManagerTest, MujocoErrorDoesNotEndTheProcess) {
  std::atomic<bool> fire{true};  // outlive the manager (the callback and listener use them)
  std::vector<EngineEvent> errors;
  Manager m(Fast());
  m.BeginPlay(TwoArms("", ""));
  m.session().engine().AddPreStepCallback([&](const mjModel*, mjData*) {
    if (fire.exchange(false)) mju_error("injected engine failure");
  });
  m.AddEventListener([&](const EngineEvent& e) {
    if (e.kind == EngineEventKind::kError) errors.push_back(e);
  });
  TickUntil(m, [&] { return !errors.empty(); });
  EXPECT_NE(errors[0].message.find("injected engine failure"), std::string::npos)
      << errors[0].message;
  EXPECT_TRUE(m.session().engine().paused());
  EXPECT_TRUE(m.playing());
  m.session().SetPaused(false);  // the simulation goes on
  TickSteps(m, 50);
}

TEST_F(ManagerTest, HostDrivenMocapBodyFollowsThePose) {
  Manager m(Fast());
  m.BeginPlay(TwoArms("", ""));
  EXPECT_THROW(m.session().SetHostDrivenPose("a", "link", {}), Error);  // not a mocap body
  EXPECT_THROW(m.session().SetHostDrivenPose("a", "nope", {}), Error);
  EXPECT_THROW(m.session().SetHostDrivenPose("z", "marker", {}), Error);
  for (int i = 0; i < 5; ++i) {
    world::Pose p;
    p.pos = {0.1 * i, -1.0 + 0.2 * i, 1.5};
    const double h = 0.3 * i / 2;
    p.quat = {2 * std::cos(h), 0, 0, 2 * std::sin(h)};  // not unit: normalised
    m.session().SetHostDrivenPose("a", "marker", p);
    TickUntil(m, [&] {
      const auto got = m.BodyPose("a", "marker");
      return got && std::abs(got->pos[0] - p.pos[0]) < 1e-12 &&
             std::abs(got->pos[1] - p.pos[1]) < 1e-12 &&
             std::abs(got->quat[3] - std::sin(h)) < 1e-12;
    });
  }
  // b's marker is not host-driven: it stays where the scene put it.
  const auto b = m.BodyPose("b", "marker");
  ASSERT_TRUE(b);
  EXPECT_NEAR(b->pos[1], 1.0, 1e-12);
  EXPECT_NEAR(b->pos[2], 2.0, 1e-12);
  EXPECT_TRUE(m.session().ClearHostDriven("a", "marker"));
  EXPECT_FALSE(m.session().ClearHostDriven("a", "marker"));
  EXPECT_FALSE(m.BodyPose("a", "nope"));
}

// Records every hook call of several subsystems in one log.
struct Probe : world::Subsystem {
  Probe(std::string n, std::vector<std::string>* l, bool fail = false)
      : name_(std::move(n)), log(l), fail_begin(fail) {}
  std::string_view name() const override { return name_; }
  void BeginPlay(world::Session& s) override {
    log->push_back(name_ + ".begin");
    EXPECT_FALSE(s.engine().running());         // before the thread starts
    frames = s.engine().SubscribeState(name_);  // its own reader, made before Start
    kept = s.shared_from_this();
    if (fail_begin) throw Error(name_ + " refuses to begin");
  }
  void Tick(world::Session&, world::TickPhase phase) override {
    if (log->size() < 40) log->push_back(name_ + ".tick" + std::to_string(static_cast<int>(phase)));
  }
  void OnEngineEvent(world::Session&, const EngineEvent& e) override {
    if (e.kind == EngineEventKind::kReset) ++resets;
  }
  void EndPlay(world::Session& s) override {
    log->push_back(name_ + ".end");
    running_at_end = s.engine().running();
  }
  std::string name_;
  std::vector<std::string>* log;
  bool fail_begin;
  int resets = 0;
  bool running_at_end = false;
  std::shared_ptr<physics::StateSubscription> frames;
  std::shared_ptr<world::Session> kept;
};

TEST_F(ManagerTest, SubsystemsBeginInOrderTickInPhasesAndEndInReverse) {
  std::vector<std::string> log;
  Manager m(Fast());
  Probe& a = static_cast<Probe&>(m.AddSubsystem(std::make_unique<Probe>("a", &log)));
  m.AddSubsystem(std::make_unique<Probe>("b", &log));
  EXPECT_THROW(m.AddSubsystem(std::make_unique<Probe>("a", &log)), Error);
  EXPECT_EQ(m.FindSubsystem("b")->name(), "b");
  EXPECT_EQ(m.FindSubsystem("c"), nullptr);
  m.BeginPlay(TwoArms("", ""));
  EXPECT_THROW(m.AddSubsystem(std::make_unique<Probe>("c", &log)), Error);
  m.Tick();
  m.session().ResetToInitialState();
  ASSERT_TRUE(WaitFor([&] { return m.session().engine().last_applied_command() > 0; }));
  m.Tick();  // delivers the reset event
  EXPECT_EQ(a.resets, 1);
  // The subsystem's own subscription sees the state without touching mjData.
  ASSERT_TRUE(WaitFor([&] { return a.frames->published() > 10; }));
  const physics::StateFrame* f = a.frames->Latest();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->qpos.size(), static_cast<std::size_t>(m.session().engine().model()->nq));
  m.EndPlay();
  const std::vector<std::string> expected_start = {"a.begin", "b.begin", "a.tick0", "b.tick0",
                                                   "a.tick1", "b.tick1", "a.tick2", "b.tick2"};
  ASSERT_GE(log.size(), expected_start.size() + 2);
  EXPECT_EQ(std::vector<std::string>(log.begin(), log.begin() + 8), expected_start);
  EXPECT_EQ(log[log.size() - 2], "b.end");
  EXPECT_EQ(log.back(), "a.end");
  EXPECT_TRUE(a.running_at_end);  // subsystems end before the engine stops
  // The session a subsystem kept is still usable (stopped) after the manager released it.
  ASSERT_NE(a.kept, nullptr);
  EXPECT_FALSE(a.kept->engine().running());
  EXPECT_EQ(a.kept->articulations().size(), 2u);
}

TEST_F(ManagerTest, SubsystemFailingToBeginEndsThoseBegunAndLeavesNothingRunning) {
  std::vector<std::string> log;
  Manager m(Fast());
  m.AddSubsystem(std::make_unique<Probe>("a", &log));
  m.AddSubsystem(std::make_unique<Probe>("b", &log, /*fail=*/true));
  m.AddSubsystem(std::make_unique<Probe>("c", &log));
  EXPECT_THROW(m.BeginPlay(TwoArms("", "")), Error);
  EXPECT_FALSE(m.playing());
  // a began and ended; b threw inside BeginPlay (it is not ended); c never began.
  EXPECT_EQ(log, (std::vector<std::string>{"a.begin", "b.begin", "a.end"}));
  Manager again(Fast());  // the world is free again
  again.BeginPlay(TwoArms("", ""));
  again.EndPlay();
}

TEST_F(ManagerTest, ExampleSceneHoldsBothArmsRaised) {
  Manager m(Fast());
  m.BeginPlay(world::LoadSceneFile(testing::SourcePath("examples/scenes/two_arms.yaml")));
  ASSERT_EQ(m.session().articulations().size(), 2u);
  TickSteps(m, 2500);  // 5 s
  for (const char* arm : {"left", "right"}) {
    const std::string p(std::string(arm) + "_");
    EXPECT_NEAR(Qpos(m, p + "shoulder"), -0.6, 0.05) << arm;  // "raised"
    EXPECT_NEAR(Qpos(m, p + "elbow"), -0.8, 0.05) << arm;
    EXPECT_NEAR(Qvel(m, p + "shoulder"), 0.0, 1e-3) << arm;
  }
}

TEST_F(ManagerTest, LoadSceneOrModelWrapsAnMjcfFile) {
  const world::SceneConfig s = world::LoadSceneOrModel(arm_);
  ASSERT_EQ(s.articulations.size(), 1u);
  EXPECT_EQ(s.articulations[0].name, "arm");
  Manager m(Fast());
  m.BeginPlay(s);
  EXPECT_GE(mj_name2id(m.session().engine().model(), mjOBJ_JOINT, "arm_hinge"), 0);
  EXPECT_THROW(world::LoadSceneOrModel(dir_ + "/missing.xml"), InputError);
}

// Another thread storms the engine and the controls while the main thread ticks and drives a
// mocap body (the TSan build runs this).
TEST_F(ManagerTest, CommandStormWhileTicking) {
  Manager m(Fast());
  const std::string pd = "    controller: {type: pd, kp: 200, kv: 20}\n    keyframe: up\n";
  m.BeginPlay(TwoArms(pd + "    hold_keyframe: true\n", pd));
  std::atomic<bool> stop{false};
  std::atomic<int> rounds{0};
  std::thread storm([&] {
    control::ArticulationControl* b = m.session().articulations()[1].control;
    for (int i = 0; !stop.load(); ++i) {
      switch (i % 8) {
        case 0:
          m.session().engine().Reset();
          break;
        case 1:
          m.session().engine().Restore(m.session().engine().Snapshot());
          break;
        case 2:
          m.session().SetPaused(i % 16 == 2);
          break;
        case 3:
          m.session().ResetArticulation("b", "down");
          break;
        case 4:
          m.session().articulations()[0].control->StopHold();
          m.session().articulations()[0].control->HoldKeyframe("a_up");
          break;
        case 5:
          m.session().controls().SetGlobalSource(i % 16 == 5 ? control::ControlSource::kUi
                                                             : control::ControlSource::kNetwork);
          break;
        case 6:
          m.session().ResetToInitialState();
          break;
        default:
          b->SetTarget(control::ControlSource::kNetwork, 0, std::sin(i));
          b->SetTarget(control::ControlSource::kUi, 0, std::cos(i));
      }
      rounds.fetch_add(1);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  // A number of storm rounds and ticks, not a span of wall time (a loaded machine runs both
  // threads slowly); the bound only ends a stalled storm.
  constexpr int kRounds = 1000, kTicks = 200;
  const auto end = Clock::now() + std::chrono::seconds(60);
  int ticks = 0;
  while ((rounds.load() < kRounds || ticks < kTicks) && Clock::now() < end) {
    world::Pose p;
    p.pos = {0.001 * ticks, -1, 2};
    m.session().SetHostDrivenPose("a", "marker", p);
    m.Tick();
    ++ticks;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  stop.store(true);
  storm.join();
  m.session().SetPaused(false);
  TickSteps(m, 10);
  EXPECT_GE(rounds.load(), kRounds);
  EXPECT_GE(ticks, kTicks);
  const physics::PhysicsState s = m.session().engine().Snapshot();
  for (double q : s.qpos) EXPECT_TRUE(std::isfinite(q));
  m.EndPlay();
}

}  // namespace
}  // namespace urlab
