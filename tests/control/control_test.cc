#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "physics/test_models.h"
#include "support/mujoco_test.h"
#include "urlab/control/articulation_control.h"
#include "urlab/control/controllers.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/views.h"

namespace urlab::control {
namespace {

using namespace std::chrono_literals;
using physics::ArticulationBindings;
using physics::CompileXmlString;
using physics::LoadXmlFile;
using physics::PhysicsEngine;
using physics::PhysicsState;
using testing::kArmXml;
using testing::kHumanoidPath;

class ControlTest : public urlab::testing::MujocoTest {};

// An engine plus a ControlSystem with one articulation per prefix.
struct ControlRig {
  explicit ControlRig(physics::ModelPtr model, std::vector<std::string> prefixes = {"arm_"})
      : engine(std::move(model)) {
    engine.WithLockedData([&](mjModel* m, mjData* d) {
      for (const auto& p : prefixes) {
        ArticulationBindings b(m, d, p);
        system.Add(std::make_unique<ArticulationControl>(b));
      }
    });
    system.Install(engine);
  }
  ArticulationControl& arm() { return *system.articulations()[0]; }
  double Qpos(const char* joint) {
    double q = 0;
    engine.WithLockedData([&](mjModel* m, mjData* d) {
      q = d->qpos[m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, joint)]];
    });
    return q;
  }
  PhysicsEngine engine;
  ControlSystem system;
};

TEST_F(ControlTest, BindingsAreSortedAndResolved) {
  physics::ModelPtr m = CompileXmlString(kArmXml);
  PdController pd;
  const int ids[] = {2, 0, 1};
  pd.Bind(m.get(), ids);
  ASSERT_EQ(pd.bindings().size(), 3u);
  EXPECT_EQ(pd.bindings()[0].actuator_id, 0);
  EXPECT_EQ(pd.bindings()[2].actuator_id, 2);
  const ActuatorBinding& motor = pd.bindings()[0];
  EXPECT_TRUE(motor.motor);
  EXPECT_EQ(motor.qpos_adr, 0);
  EXPECT_EQ(motor.dof_adr, 0);
  EXPECT_TRUE(motor.joint_limited);
  EXPECT_FALSE(pd.bindings()[1].motor);  // position servo
  EXPECT_FALSE(pd.bindings()[2].motor);  // filtered
  EXPECT_EQ(pd.IndexOfActuator(1), 1);
  EXPECT_EQ(pd.IndexOfActuator(9), -1);
}

TEST_F(ControlTest, PdLawClampsTargetAndTorque) {
  physics::ModelPtr m = CompileXmlString(kArmXml);
  physics::DataPtr d = physics::MakeData(m.get());
  PdController pd(PdGains{1, 0, 1e9});
  const int ids[] = {0, 1};
  pd.Bind(m.get(), ids);
  const double targets[] = {5.0, 7.0};  // both beyond the joint ranges (2, 2.5)
  pd.ComputeAndApply(m.get(), d.get(), targets);
  EXPECT_DOUBLE_EQ(d->ctrl[0], 2.0);  // kp * (clamp(5) - 0) / (gain 1 * gear 1)
  EXPECT_DOUBLE_EQ(d->ctrl[1], 2.5);  // servo receives the clamped target
  pd.SetGains(0, PdGains{1000, 0, 3});
  pd.ComputeAndApply(m.get(), d.get(), targets);
  EXPECT_DOUBLE_EQ(d->ctrl[0], 3.0);  // torque limit
  pd.SetGains(0, PdGains{1e6, 0, 1e9});
  pd.ComputeAndApply(m.get(), d.get(), targets);
  EXPECT_DOUBLE_EQ(d->ctrl[0], 50.0);  // ctrlrange
  EXPECT_EQ(pd.gains(0).kp, 1e6);
  EXPECT_THROW(pd.SetGains(5, {}), Error);
}

TEST_F(ControlTest, PdHeldJointSettlesAtTarget) {
  ControlRig rig(CompileXmlString(kArmXml));
  PdController& pd = rig.arm().Use(std::make_unique<PdController>(PdGains{400, 40}));
  EXPECT_EQ(pd.bindings().size(), 3u);
  rig.arm().SetTarget(ControlSource::kNetwork, "shoulder_motor", 0.6);
  rig.arm().SetTarget(ControlSource::kNetwork, "elbow_servo", -0.4);
  rig.engine.StepSync(1500);                         // 3 s
  EXPECT_NEAR(rig.Qpos("arm_shoulder"), 0.6, 0.02);  // gravity error ~ m g l / kp
  EXPECT_NEAR(rig.Qpos("arm_elbow"), -0.4, 0.1);     // MuJoCo servo, kp = 20
  // Velocity has died out: it is held, not passing through.
  rig.engine.WithLockedData([](mjModel*, mjData* d) { EXPECT_NEAR(d->qvel[0], 0, 1e-3); });
}

TEST_F(ControlTest, ControlSourceGlobalAndOverride) {
  ControlRig rig(CompileXmlString(kArmXml));
  ArticulationControl& arm = rig.arm();
  arm.SetTarget(ControlSource::kNetwork, 0, 1.5);
  arm.SetTarget(ControlSource::kUi, 0, -2.5);
  auto ctrl0 = [&] {
    double u = 0;
    rig.engine.WithLockedData([&](mjModel*, mjData* d) { u = d->ctrl[0]; });
    return u;
  };
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl0(), 1.5);  // default global source: network
  rig.system.SetGlobalSource(ControlSource::kUi);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl0(), -2.5);
  arm.SetSourceOverride(ControlSource::kNetwork);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl0(), 1.5);
  EXPECT_EQ(arm.EffectiveSource(ControlSource::kUi), ControlSource::kNetwork);
  arm.SetSourceOverride(std::nullopt);
  EXPECT_EQ(arm.EffectiveSource(ControlSource::kUi), ControlSource::kUi);
  EXPECT_FALSE(arm.SetTarget(ControlSource::kUi, "nope", 1));
  EXPECT_FALSE(arm.SetTarget(ControlSource::kUi, 17, 1));
  EXPECT_STREQ(ToString(ControlSource::kUi), "ui");
}

TEST_F(ControlTest, KeyframeControllerPassesPosesInOrder) {
  ControlRig rig(CompileXmlString(kArmXml));
  KeyframeController::Options options;
  options.start_delay = 0.1;
  KeyframeController& kc =
      rig.arm().Use(std::make_unique<KeyframeController>(options, PdGains{400, 40}));
  std::vector<double> up(3, 0), down(3, 0);
  up[0] = 0.5;
  up[1] = 0.3;
  down[0] = -0.5;
  down[1] = -0.3;
  kc.AddPose({"up", up, 0.2, 0.5});
  kc.AddPose({"down", down, 0.2, 0.5});
  EXPECT_THROW(kc.AddPose({"bad", {1.0}, 0.1, 0.1}), Error);

  // Expected timeline: wait [0, .1), blend up [.1, .3), hold up [.3, .8), blend down [.8, 1.0),
  // hold down [1.0, 1.5), then hold down forever.
  struct Sample {
    double t;
    int pose;
    bool blending;
  };
  const Sample expect[] = {{0.05, -1, false}, {0.2, 0, true},  {0.5, 0, false},
                           {0.9, 1, true},    {1.2, 1, false}, {2.0, 1, false}};
  double shoulder_end_of_up = 0, shoulder_end = 0;
  for (const Sample& s : expect) {
    while (true) {
      double t = 0;
      rig.engine.WithLockedData([&](mjModel*, mjData* d) { t = d->time; });
      if (t >= s.t) break;
      rig.engine.StepSync(1);
      if (std::abs(t - 0.79) < 1e-6) shoulder_end_of_up = rig.Qpos("arm_shoulder");
    }
    EXPECT_EQ(kc.current_pose(), s.pose) << "t=" << s.t;
    EXPECT_EQ(kc.blending(), s.blending) << "t=" << s.t;
  }
  shoulder_end = rig.Qpos("arm_shoulder");
  EXPECT_TRUE(kc.playing());
  EXPECT_NEAR(shoulder_end_of_up, 0.5, 0.03);  // reached and held "up"
  EXPECT_NEAR(shoulder_end, -0.5, 0.03);       // and then "down"
  kc.Stop();
  rig.engine.StepSync(1);
  EXPECT_FALSE(kc.playing());
  EXPECT_EQ(kc.current_pose(), -1);
}

TEST_F(ControlTest, KeyframeControllerLoopsAndEases) {
  EXPECT_DOUBLE_EQ(KeyframeController::Ease(0), 0);
  EXPECT_DOUBLE_EQ(KeyframeController::Ease(0.5), 0.5);
  EXPECT_DOUBLE_EQ(KeyframeController::Ease(1), 1);
  EXPECT_DOUBLE_EQ(KeyframeController::Ease(2), 1);
  EXPECT_LT(KeyframeController::Ease(0.1), 0.1);  // slow start
  EXPECT_GT(KeyframeController::Ease(0.9), 0.9);  // slow end

  ControlRig rig(CompileXmlString(kArmXml));
  KeyframeController::Options options;
  options.loop = true;
  options.autoplay = false;
  KeyframeController& kc = rig.arm().Use(std::make_unique<KeyframeController>(options));
  const int bent = mj_name2id(rig.engine.model(), mjOBJ_KEY, "arm_bent");
  kc.AddPose(kc.PoseFromModelKey(rig.engine.model(), bent, 0.1, 0.1));
  EXPECT_DOUBLE_EQ(kc.poses()[0].positions[0], 0.8);
  EXPECT_DOUBLE_EQ(kc.poses()[0].positions[1], -1.2);
  std::vector<double> zero(3, 0);
  kc.AddPose({"zero", zero, 0.1, 0.1});
  rig.engine.StepSync(10);
  EXPECT_FALSE(kc.playing());  // no autoplay
  kc.Play();
  rig.engine.StepSync(1);  // starts at t = 0.02
  EXPECT_TRUE(kc.playing());
  // One cycle is 0.4 s; at 0.45 s after the start we are blending into pose 0 again.
  rig.engine.StepSync(225);
  EXPECT_EQ(kc.current_pose(), 0);
  EXPECT_TRUE(kc.blending());
}

TEST_F(ControlTest, SnapshotDeterminismWithControllersActive) {
  ControlRig rig(LoadXmlFile(kHumanoidPath), {""});
  rig.arm().Use(std::make_unique<PdController>(PdGains{5, 0.5}));
  for (int i = 0; i < rig.arm().num_actuators(); ++i) {
    rig.arm().SetTarget(ControlSource::kNetwork, i, 0.3 * std::sin(i));
  }
  rig.engine.StepSync(1000);
  const PhysicsState snap = rig.engine.Snapshot();
  auto run = [&] {
    rig.engine.StepSync(500);
    rig.engine.Reset();
    rig.engine.StepSync(500);
    return rig.engine.Snapshot();
  };
  const PhysicsState a = run();
  rig.engine.Restore(snap);
  const PhysicsState b = run();
  EXPECT_TRUE(a.BitwiseEquals(b));

  // Time-driven keyframe controller on the arm: replays identically after restore.
  ControlRig arm(CompileXmlString(kArmXml));
  KeyframeController& kc = arm.arm().Use(std::make_unique<KeyframeController>());
  std::vector<double> p(3, 0.4);
  kc.AddPose({"p", p, 0.3, 0.2});
  kc.AddPose({"q", std::vector<double>(3, -0.4), 0.3, 0.2});
  arm.engine.StepSync(100);
  const PhysicsState s2 = arm.engine.Snapshot();
  arm.engine.StepSync(1000);
  const PhysicsState a2 = arm.engine.Snapshot();
  arm.engine.Restore(s2);
  arm.engine.StepSync(1000);
  EXPECT_TRUE(a2.BitwiseEquals(arm.engine.Snapshot()));
}

TEST_F(ControlTest, ArticulationKeyframeResetLeavesOthersAlone) {
  ControlRig rig(CompileXmlString(kArmXml), {"arm_", "box"});
  rig.engine.StepSync(200);  // arm swings, box settles
  rig.engine.WithLockedData([](mjModel*, mjData* d) {
    d->qpos[0] = 0.3;
    d->qpos[2] = 0.9;  // box x
  });
  const PhysicsState before = rig.engine.Snapshot();
  rig.system.RequestKeyframeReset(rig.engine, "arm_", "bent");  // prefix + name resolution
  const PhysicsState after = rig.engine.Snapshot();
  EXPECT_DOUBLE_EQ(after.qpos[0], 0.8);
  EXPECT_DOUBLE_EQ(after.qpos[1], -1.2);
  EXPECT_EQ(after.qvel[0], 0.0);
  EXPECT_EQ(after.time, before.time);  // a partial reset keeps the clock
  for (int k = 2; k < 9; ++k) EXPECT_EQ(after.qpos[k], before.qpos[k]) << k;  // box untouched
  for (int k = 2; k < 8; ++k) EXPECT_EQ(after.qvel[k], before.qvel[k]) << k;
  auto events = rig.engine.DrainEvents();
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.back().message.find("reset articulation 'arm_'"), std::string::npos);
  EXPECT_THROW(rig.system.RequestKeyframeReset(rig.engine, "arm_", "nope"), Error);
  EXPECT_THROW(rig.system.RequestKeyframeReset(rig.engine, "robot_", "bent"), Error);
}

TEST_F(ControlTest, HoldKeyframeKeepsThePoseUntilStopped) {
  ControlRig rig(CompileXmlString(kArmXml));
  rig.arm().Use(std::make_unique<PdController>(PdGains{400, 40}));
  rig.arm().HoldKeyframe("arm_bent");
  EXPECT_TRUE(rig.arm().holding());
  rig.engine.StepSync(1500);
  EXPECT_NEAR(rig.Qpos("arm_shoulder"), 0.8, 0.03);
  EXPECT_NEAR(rig.Qpos("arm_elbow"), -1.2, 0.1);
  rig.arm().StopHold();  // back to the (zero) network targets
  rig.engine.StepSync(1500);
  EXPECT_NEAR(rig.Qpos("arm_shoulder"), 0.0, 0.03);
  EXPECT_THROW(rig.arm().HoldKeyframe("nope"), Error);
}

// Control writes, gain changes, source flips and holds from other threads while the loop runs.
TEST_F(ControlTest, StressControlWritesWhileRunning) {
  ControlRig rig(CompileXmlString(kArmXml));
  PdController& pd = rig.arm().Use(std::make_unique<PdController>());
  rig.engine.SetAsFastAsPossible(true);
  rig.engine.Start();
  std::atomic<bool> done{false};
  std::thread writer([&] {
    int i = 0;
    while (!done.load()) {
      rig.arm().SetTarget(i % 2 ? ControlSource::kUi : ControlSource::kNetwork, i % 3,
                          std::sin(0.01 * i));
      pd.SetGains(i % 3, PdGains{50.0 + i % 10, 5});
      if (i % 100 == 0)
        rig.system.SetGlobalSource(i % 200 ? ControlSource::kUi : ControlSource::kNetwork);
      if (i % 250 == 0) rig.arm().HoldKeyframe(i % 500 ? "arm_home" : "arm_bent");
      if (i % 250 == 125) rig.arm().StopHold();
      if (i % 400 == 0) rig.system.RequestKeyframeReset(rig.engine, "arm_", "home");
      ++i;
    }
  });
  // Runs a number of steps, not a span of wall time (a loaded machine steps slowly); the bound
  // only ends a stalled engine.
  constexpr std::uint64_t kSteps = 5000;
  const auto end = std::chrono::steady_clock::now() + 60s;
  while (rig.engine.step_count() < kSteps && std::chrono::steady_clock::now() < end) {
    rig.engine.PollEvents();
    std::this_thread::sleep_for(2ms);
  }
  done = true;
  writer.join();
  rig.engine.Stop();
  EXPECT_GE(rig.engine.step_count(), kSteps);
}

}  // namespace
}  // namespace urlab::control
