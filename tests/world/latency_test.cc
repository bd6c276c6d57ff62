// Emulated latency on a real session stepped in lockstep (StepSync): the control that reaches
// the actuators is the one sent exactly k steps earlier; the observation an observed subscriber
// (the network's) reads is the true state k steps earlier while the recorder's subscription sees
// the true state; jitter stays within its bounds and never reorders; the same seed gives the
// same trajectory; the scene's `latency:` section is parsed and checked with file:line.
#include "urlab/physics/latency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "mujoco_test.h"
#include "urlab/core/error.h"
#include "urlab/world/scene.h"
#include "urlab/world/scene_file.h"
#include "urlab/world/session.h"

namespace urlab {
namespace {

// A pendulum with a motor and a joint-position sensor: every step moves it, every ctrl shows.
constexpr const char* kLatencyArmXml = R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.01"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" gear="1" ctrllimited="true" ctrlrange="-1000 1000"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
</mujoco>)";

class LatencyTest : public testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("latency");
    testing::WriteTextFile(dir_, "arm.xml", kLatencyArmXml);
  }
  world::SceneConfig Scene(const std::string& extra = "", const std::string& top = "") {
    return world::ParseScene(top + "articulations:\n  - name: arm\n    mjcf: arm.xml\n" + extra,
                             dir_ + "/scene.yaml");
  }
  std::string dir_;
};

double Ctrl(world::Session& s) {
  double u = 0;
  s.engine().WithLockedData([&](mjModel*, mjData* d) { u = d->ctrl[0]; });
  return u;
}

// Sends target 100 + i before step i, steps once, returns the ctrl each step applied.
std::vector<double> DriveSteps(world::Session& s, int n) {
  control::ArticulationControl& c = *s.Require("arm").control;
  std::vector<double> applied;
  for (int i = 0; i < n; ++i) {
    const double target = 100 + i;
    c.PublishFrame(control::ControlSource::kNetwork, std::span<const double>(&target, 1));
    s.engine().StepSync(1);
    applied.push_back(Ctrl(s));
  }
  return applied;
}

TEST_F(LatencyTest, ControlTakesEffectExactlyKStepsAfterItArrives) {
  for (int k : {0, 1, 4}) {
    auto s = world::Session::Create(
        Scene("    latency:\n      control: {delay_steps: " + std::to_string(k) + "}\n"));
    const std::vector<double> applied = DriveSteps(*s, 20);
    for (int i = 0; i < 20; ++i) {
      // Before the first command matured the actuator holds the command in effect when the
      // delay started (the seeded initial target, 0).
      const double want = i >= k ? 100 + (i - k) : 0;
      EXPECT_EQ(applied[static_cast<std::size_t>(i)], want) << "k=" << k << " step " << i;
    }
  }
}

TEST_F(LatencyTest, ControlDelayInSecondsIsRoundedToSteps) {
  auto s = world::Session::Create(Scene("    latency:\n      control: {delay: 0.0061}\n"));
  const std::vector<double> applied = DriveSteps(*s, 10);
  EXPECT_EQ(applied[3], 100);  // round(0.0061 / 0.002) = 3 steps
  EXPECT_EQ(applied[9], 106);
}

TEST_F(LatencyTest, ControlJitterStaysWithinBoundsAndSameSeedSameTrajectory) {
  const std::string latency = "    latency:\n      control: {delay_steps: 3, jitter_steps: 2}\n";
  auto a = world::Session::Create(Scene(latency, "seed: 11\n"));
  auto b = world::Session::Create(Scene(latency, "seed: 11\n"));
  auto c = world::Session::Create(Scene(latency, "seed: 12\n"));
  const std::vector<double> ra = DriveSteps(*a, 400);
  std::map<int, int> lags;
  double last = 0;
  for (int i = 10; i < 400; ++i) {
    const double u = ra[static_cast<std::size_t>(i)];
    EXPECT_GE(u, last);  // never reordered
    last = u;
    const int lag = i - static_cast<int>(u - 100);
    EXPECT_GE(lag, 1);
    EXPECT_LE(lag, 5);
    ++lags[lag];
  }
  EXPECT_EQ(lags.size(), 5u);  // every lag 1..5 occurs
  EXPECT_EQ(ra, DriveSteps(*b, 400));
  EXPECT_NE(ra, DriveSteps(*c, 400));
  // The same controls give the same trajectory, bit for bit.
  a->engine().WithLockedData([&](mjModel*, mjData* da) {
    b->engine().WithLockedData([&](mjModel*, mjData* db) {
      EXPECT_EQ(da->qpos[0], db->qpos[0]);
      EXPECT_EQ(da->qvel[0], db->qvel[0]);
    });
  });
}

TEST_F(LatencyTest, ObservedStateIsTheTrueStateKStepsEarlier) {
  constexpr int kDelay = 5;
  auto s = world::Session::Create(
      Scene("    latency:\n      observation: {delay_steps: " + std::to_string(kDelay) + "}\n"));
  auto observed = s->engine().SubscribeState("observer", /*observed=*/true);
  auto truth = s->engine().SubscribeEveryStep("truth", 256);
  std::map<std::uint64_t, std::pair<double, double>> true_by_step;  // qpos, sensor
  s->engine().WithLockedData([&](mjModel*, mjData* d) {
    true_by_step[0] = {d->qpos[0], d->sensordata[0]};
  });
  physics::StateFrame f;
  for (int i = 0; i < 60; ++i) {
    s->engine().StepSync(1);
    while (truth->TryPop(&f)) true_by_step[f.step] = {f.qpos[0], f.sensordata[0]};
    const physics::StateFrame* o = observed->Latest();
    ASSERT_NE(o, nullptr);
    const std::uint64_t step = o->step;
    ASSERT_TRUE(true_by_step.count(step));
    // Time and step are current; the articulation's values are those of kDelay steps earlier.
    EXPECT_EQ(o->time, s->engine().Snapshot().time);
    if (step >= static_cast<std::uint64_t>(kDelay)) {
      EXPECT_EQ(o->qpos[0], true_by_step.at(step - kDelay).first) << "step " << step;
      EXPECT_EQ(o->sensordata[0], true_by_step.at(step - kDelay).second) << "step " << step;
      EXPECT_NE(o->qpos[0], true_by_step.at(step).first) << "step " << step;
    }
  }
}

TEST_F(LatencyTest, ResetRestartsTheDelaysWithTheSameDraws) {
  const std::string latency = "    latency:\n      control: {delay_steps: 2, jitter_steps: 1}\n";
  auto s = world::Session::Create(Scene(latency, "seed: 3\n"));
  const std::vector<double> first = DriveSteps(*s, 50);
  // The command in effect at the reset is held until the first delayed one: the same as at the
  // start, so the same requests give the same controls.
  const double zero = 0;
  s->Require("arm").control->PublishFrame(control::ControlSource::kNetwork,
                                          std::span<const double>(&zero, 1));
  s->ResetToInitialState();
  const std::vector<double> second = DriveSteps(*s, 50);
  EXPECT_EQ(first, second);
}

TEST_F(LatencyTest, SetLatencyAtRunTimeAndItsSetting) {
  auto s = world::Session::Create(Scene());
  EXPECT_EQ(DriveSteps(*s, 3)[2], 102);  // no delay
  physics::ArticulationLatency l;
  l.control.delay = 2;
  s->SetLatency("arm", l, 9);
  EXPECT_EQ(s->Latency("arm"), l);
  EXPECT_EQ(s->latency_seed(), 9u);
  const std::vector<double> applied = DriveSteps(*s, 5);
  EXPECT_EQ(applied[4], 102);  // target 100 + 2 sent two steps before
  EXPECT_THROW(s->SetLatency("nobody", l), Error);
}

TEST_F(LatencyTest, BadLatencySectionsNameTheirLine) {
  const auto fails = [&](const std::string& extra, const std::string& needle) {
    try {
      Scene(extra);
      ADD_FAILURE() << "accepted: " << extra;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("scene.yaml:"), std::string::npos) << e.what();
    }
  };
  fails("    latency:\n      control: {lag: 3}\n", "unknown latency key 'lag'");
  fails("    latency:\n      control: {delay_steps: 1.5}\n", "whole number");
  fails("    latency:\n      control: {delay_steps: 1, delay: 0.1}\n", "not both");
  fails("    latency:\n      observation: {jitter: -1}\n", ">= 0");
  fails("    latency:\n      actuators: {}\n", "unknown key 'actuators'");
  fails("    latency: 3\n", "mapping");
  fails("    latency:\n      cameras: {eye: {delay: 0.1}}\n", "unknown key 'cameras'");
}

// Issue 38, case 3: a latency's ticks (delay + jitter + the rate cap's interval) size a buffer,
// so they are bounded: a tiny rate_hz (1e-5 Hz held values for 50,000,000 steps, 1.6 GB) or a
// delay in seconds over a tiny timestep is refused by validate and by the session, naming the
// articulation, the channel, the fields and the limit; resolving never overflows an int.
TEST_F(LatencyTest, LatencyTicksAreBounded) {
  const auto refused = [&](const std::string& extra, const std::string& field,
                           const std::string& top = "") {
    testing::WriteTextFile(dir_, "bounded.yaml",
                           top + "articulations:\n  - name: arm\n    mjcf: arm.xml\n" + extra);
    const world::ValidationReport r = world::Validate(dir_ + "/bounded.yaml");
    EXPECT_FALSE(r.ok()) << extra;
    std::string all;
    for (const auto& d : r.diagnostics.all()) all += d.where.str() + ": " + d.message + "\n";
    EXPECT_NE(all.find("bounded.yaml:"), std::string::npos) << all;
    EXPECT_NE(all.find("arm.latency." + field), std::string::npos) << all;
    EXPECT_NE(all.find("1000000 steps"), std::string::npos) << all;
  };
  refused("    latency:\n      observation: {rate_hz: 0.00001}\n", "observation");
  refused("    latency:\n      control: {rate_hz: 1e-12}\n", "control");
  refused("    latency:\n      control: {delay_steps: 600000, jitter_steps: 600000}\n", "control");
  // Within the limit: fine (delay 1000000 steps alone would be too, with nothing beside it).
  testing::WriteTextFile(dir_, "fine.yaml",
                         "articulations:\n  - name: arm\n    mjcf: arm.xml\n    latency:\n"
                         "      observation: {rate_hz: 1, delay_steps: 5}\n");
  EXPECT_TRUE(world::Validate(dir_ + "/fine.yaml").ok());

  // ResolveLatency saturates instead of overflowing (a caller that did not check).
  physics::LatencySetting tiny;
  ASSERT_EQ(physics::SetLatencyKey(&tiny, "rate_hz", 1e-12), "");
  const physics::DelaySpec spec = physics::ResolveLatency(tiny, 0.002, 1);
  EXPECT_GT(spec.min_interval, 1);
  EXPECT_LE(spec.min_interval, 1000000);  // physics::kMaxLatencySteps
  physics::LatencySetting long_delay;
  ASSERT_EQ(physics::SetLatencyKey(&long_delay, "delay", 60), "");
  const physics::DelaySpec d = physics::ResolveLatency(long_delay, 1e-12, 1);
  EXPECT_GT(d.delay, 0);
  EXPECT_LE(d.delay, 1000000);
}

}  // namespace
}  // namespace urlab
