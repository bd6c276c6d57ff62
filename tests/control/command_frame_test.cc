// Command frames: a whole multi-actuator command is applied whole (never half old, half new),
// gains arrive with their targets, and the named sources switch atomically. Run under TSan in CI.
#include "urlab/control/command_frame.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "support/mujoco_test.h"
#include "support/wait.h"
#include "urlab/control/articulation_control.h"
#include "urlab/control/controllers.h"
#include "urlab/physics/engine.h"
#include "urlab/physics/views.h"

namespace urlab::control {
namespace {

using physics::PhysicsEngine;
using testing::WaitFor;

class CommandFrameTest : public urlab::testing::MujocoTest {};

// A robot with `n` unclamped motors (passthrough writes targets straight into ctrl).
std::string Motors(int n) {
  std::string bodies, actuators;
  for (int i = 0; i < n; ++i) {
    const std::string j = "r_j" + std::to_string(i);
    bodies += "<body name=\"r_b" + std::to_string(i) + "\" pos=\"" + std::to_string(i) +
              " 0 1\"><joint name=\"" + j +
              "\" axis=\"0 1 0\" damping=\"1\"/><geom size=\"0.05\" mass=\"1\"/></body>";
    actuators += "<motor name=\"r_m" + std::to_string(i) + "\" joint=\"" + j + "\"/>";
  }
  return "<mujoco><option gravity=\"0 0 0\"/><worldbody>" + bodies + "</worldbody><actuator>" +
         actuators + "</actuator></mujoco>";
}

struct Rig {
  explicit Rig(int n) : engine(physics::CompileXmlString(Motors(n))) {
    engine.WithLockedData([&](mjModel* m, mjData* d) {
      physics::ArticulationBindings b(m, d, "r_");
      robot = &system.Add(std::make_unique<ArticulationControl>(b));
    });
    system.Install(engine);
  }
  PhysicsEngine engine;
  ControlSystem system;
  ArticulationControl* robot = nullptr;
};

// A writer thread publishes frames whose targets are all equal to the frame's number, as fast as
// it can; the physics thread checks after every step that all 29 controls came from one frame.
TEST_F(CommandFrameTest, PhysicsThreadNeverSeesAMixedFrame) {
  constexpr int kN = 29;
  Rig rig(kN);
  rig.engine.SetAsFastAsPossible(true);
  std::atomic<long> mixed{0}, checked{0}, from_ui{0};
  std::atomic<double> newest_seen{0};
  rig.engine.AddPostStepCallback([&](const mjModel* m, mjData* d) {
    for (int i = 1; i < m->nu; ++i) {
      if (d->ctrl[i] != d->ctrl[0]) {
        mixed.fetch_add(1);
        break;
      }
    }
    if (d->ctrl[0] == 1e6) from_ui.fetch_add(1);
    newest_seen.store(d->ctrl[0]);
    checked.fetch_add(1);
  });
  std::atomic<bool> done{false};
  std::atomic<long> published{0};
  std::thread writer([&] {
    std::vector<double> frame(kN);
    for (long k = 1; !done.load(); ++k) {
      // Each frame differs from the last (sign and size) but stays small, so the robot stays sane.
      std::fill(frame.begin(), frame.end(), (k % 2 ? 1.0 : -1.0) * (1 + k % 1000) * 1e-3);
      ASSERT_TRUE(rig.robot->PublishFrame(ControlSource::kNetwork, frame));
      published.store(k);
    }
  });
  // A second writer patches single values of another source; never active, never seen.
  std::thread patcher([&] {
    for (int k = 0; !done.load(); ++k) rig.robot->SetTarget(ControlSource::kUi, k % kN, 1e6);
  });
  rig.engine.Start();
  ASSERT_TRUE(WaitFor([&] { return checked.load() > 20000 && published.load() > 20000; }));
  done = true;
  writer.join();
  patcher.join();
  rig.engine.Stop();
  EXPECT_EQ(mixed.load(), 0) << "of " << checked.load() << " steps";
  EXPECT_NE(newest_seen.load(), 0.0);
  EXPECT_EQ(from_ui.load(), 0);  // the UI source was never applied
}

TEST_F(CommandFrameTest, ChannelPublishesWholeFramesAndPatches) {
  FrameChannel c(3);
  const CommandFrame& initial = c.Read();
  EXPECT_EQ(initial.seq, 0u);
  EXPECT_EQ(initial.targets, (std::vector<double>{0, 0, 0}));
  EXPECT_TRUE(std::isnan(initial.kp[0]));
  const std::vector<double> t = {1, 2, 3};
  EXPECT_FALSE(c.Publish(std::vector<double>{1, 2}));  // wrong size: nothing published
  EXPECT_FALSE(c.Publish(t, std::vector<double>{1}));
  EXPECT_TRUE(c.Publish(t));
  EXPECT_TRUE(c.Set(1, 20));
  EXPECT_FALSE(c.Set(3, 0));
  const std::pair<int, double> bad[] = {{0, 5}, {7, 1}};
  EXPECT_FALSE(c.Patch(bad));  // all or nothing
  EXPECT_EQ(c.Targets(), (std::vector<double>{1, 20, 3}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(c.Publish(t, std::vector<double>{10, nan, 30}, {}));
  EXPECT_TRUE(c.Publish(t, std::vector<double>{nan, 11, nan}, std::vector<double>{1, 1, 1}));
  const CommandFrame& f = c.Read();
  EXPECT_EQ(f.seq, 4u);
  EXPECT_EQ(f.seq, c.last_seq());
  EXPECT_EQ(f.targets, t);
  EXPECT_EQ(f.kp, (std::vector<double>{10, 11, 30}));  // gain patches accumulate
  EXPECT_EQ(f.kv, (std::vector<double>{1, 1, 1}));
  // Gains alone: the targets stay, NaN keeps a gain, a wrong size publishes nothing.
  EXPECT_FALSE(c.PatchGains(std::vector<double>{1}, {}));
  EXPECT_TRUE(c.PatchGains(std::vector<double>{nan, 12, nan}, {}));
  const CommandFrame& g = c.Read();
  EXPECT_EQ(g.seq, 5u);
  EXPECT_EQ(g.targets, t);
  EXPECT_EQ(g.kp, (std::vector<double>{10, 12, 30}));
  EXPECT_EQ(c.Gains(1), (std::pair<double, double>{12, 1}));
}

// Gains that arrive with a frame drive the PD law from the same step as their targets.
TEST_F(CommandFrameTest, FrameGainsOverrideThePdGains) {
  Rig rig(1);
  rig.robot->Use(std::make_unique<PdController>(PdGains{100, 0, 1e9}));
  rig.robot->PublishFrame(ControlSource::kNetwork, std::vector<double>{0.5});
  rig.engine.StepSync(1);
  double ctrl = 0;
  rig.engine.WithLockedData([&](mjModel*, mjData* d) { ctrl = d->ctrl[0]; });
  EXPECT_NEAR(ctrl, 100 * 0.5, 1e-3);
  rig.engine.Reset();
  rig.robot->PublishFrame(ControlSource::kNetwork, std::vector<double>{0.5}, std::vector<double>{7},
                          std::vector<double>{0});
  rig.engine.StepSync(1);
  rig.engine.WithLockedData([&](mjModel*, mjData* d) { ctrl = d->ctrl[0]; });
  EXPECT_NEAR(ctrl, 7 * 0.5, 1e-3);
}

// A raw frame's targets are the controls as they are: the PD controller does not run on it, until
// a patch says controller again (the step server's control_mode). The flag stays across patches
// that do not name it.
TEST_F(CommandFrameTest, RawFramesBypassTheController) {
  Rig rig(1);
  rig.robot->Use(std::make_unique<PdController>(PdGains{100, 0, 1e9}));
  FrameChannel& net = rig.robot->channel(ControlSource::kNetwork);
  const auto step_ctrl = [&] {
    rig.engine.StepSync(1);
    double c = 0;
    rig.engine.WithLockedData([&](mjModel*, mjData* d) { c = d->ctrl[0]; });
    return c;
  };
  const std::pair<int, double> target{0, 0.25};
  ASSERT_TRUE(net.Patch(std::span(&target, 1), true));
  EXPECT_EQ(step_ctrl(), 0.25);
  const std::pair<int, double> next{0, 0.5};
  ASSERT_TRUE(net.Patch(std::span(&next, 1)));  // still raw
  EXPECT_EQ(step_ctrl(), 0.5);
  ASSERT_TRUE(net.Patch({}, false));  // the controller's target again
  rig.engine.Reset();
  EXPECT_NEAR(step_ctrl(), 100 * 0.5, 1e-3);
}

// The active source switches atomically between whole frames of each source; hold wins while
// holding and gives control back on StopHold.
TEST_F(CommandFrameTest, NamedSourcesSwitchWholeFrames) {
  Rig rig(2);
  const auto ctrl = [&] {
    std::vector<double> c(2);
    rig.engine.WithLockedData([&](mjModel*, mjData* d) { c.assign(d->ctrl, d->ctrl + 2); });
    return c;
  };
  for (int s = 0; s < kNumControlSources; ++s) {
    const auto src = static_cast<ControlSource>(s);
    rig.robot->PublishFrame(src, std::vector<double>{s + 0.1, s + 0.2});
    EXPECT_EQ(ParseControlSource(ToString(src)), src);
  }
  EXPECT_EQ(ParseControlSource("joystick"), std::nullopt);
  rig.system.SetGlobalSource(ControlSource::kNetwork);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl(), (std::vector<double>{0.1, 0.2}));
  rig.robot->SetSourceOverride(ControlSource::kReplay);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl(), (std::vector<double>{4.1, 4.2}));
  rig.robot->SetSourceOverride(ControlSource::kInput);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl(), (std::vector<double>{2.1, 2.2}));
  rig.robot->SetSourceOverride(std::nullopt);
  rig.system.SetGlobalSource(ControlSource::kUi);
  rig.engine.StepSync(1);
  EXPECT_EQ(ctrl(), (std::vector<double>{1.1, 1.2}));
  EXPECT_EQ(rig.robot->EffectiveSource(ControlSource::kUi), ControlSource::kUi);
}

// Every published frame carries the command frames its step applied (what a recorder keeps): the
// targets and gain overrides of the active source, its publication number and the source.
TEST_F(CommandFrameTest, StateFramesCarryTheAppliedCommandFrames) {
  Rig rig(3);
  ASSERT_EQ(rig.engine.command_layout().size(), 1u);
  EXPECT_EQ(rig.engine.command_layout()[0].name, "r");
  EXPECT_EQ(rig.engine.command_layout()[0].actuators, (std::vector<int>{0, 1, 2}));
  auto ring = rig.engine.SubscribeEveryStep("test", 16);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(rig.robot->PublishFrame(ControlSource::kNetwork, std::vector<double>{1, 2, 3},
                                      std::vector<double>{5, nan, nan}));
  rig.engine.StepSync(1);
  physics::StateFrame f;
  ASSERT_TRUE(ring->TryPop(&f));
  EXPECT_EQ(f.commands.targets, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(f.commands.kp[0], 5.0);
  EXPECT_TRUE(std::isnan(f.commands.kp[1]) && std::isnan(f.commands.kv[0]));
  EXPECT_EQ(f.commands.seq,
            (std::vector<std::uint64_t>{rig.robot->channel(ControlSource::kNetwork).last_seq()}));
  EXPECT_EQ(f.commands.source,
            (std::vector<std::uint8_t>{static_cast<std::uint8_t>(ControlSource::kNetwork)}));
  rig.robot->SetSourceOverride(ControlSource::kUi);
  ASSERT_TRUE(rig.robot->SetTarget(ControlSource::kUi, 2, 9));
  rig.engine.StepSync(1);
  ASSERT_TRUE(ring->TryPop(&f));
  EXPECT_EQ(f.commands.targets, (std::vector<double>{0, 0, 9}));
  EXPECT_EQ(f.commands.source[0], static_cast<std::uint8_t>(ControlSource::kUi));
  EXPECT_EQ(f.ctrl, (std::vector<double>{0, 0, 9}));  // passthrough: what the frame asked
}

}  // namespace
}  // namespace urlab::control
