// The C++ client against a real network subsystem on loopback (ephemeral ports): discovery,
// control by name read back from the state topics, gains, and lockstep through the step server.
#include "urlab/client/client.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "support/mujoco_test.h"
#include "urlab/net/network.h"
#include "urlab/world/manager.h"

namespace urlab::client {
namespace {

using namespace std::chrono_literals;

class ClientTest : public urlab::testing::MujocoTest {
 protected:
  void SetUp() override {
    net::NetworkOptions o;
    o.state = o.control = o.info = o.rpc = "tcp://127.0.0.1:*";
    net_ = &static_cast<net::NetworkSubsystem&>(
        manager_.AddSubsystem(std::make_unique<net::NetworkSubsystem>(o)));
    manager_.BeginPlay(
        world::ParseScene("control_source: network\n"
                          "articulations:\n"
                          "  - {name: arm, mjcf: " +
                              urlab::testing::SourcePath("examples/models/servo_arm.xml") +
                              ", controller: {type: pd, kp: 400, kv: 20}}\n",
                          urlab::testing::MakeTempDir("client") + "/scene.yaml"));
    endpoints_.state = net_->endpoints().state;
    endpoints_.control = net_->endpoints().control;
    endpoints_.info = net_->endpoints().info;
    endpoints_.rpc = net_->endpoints().rpc;
  }
  world::Manager manager_;
  net::NetworkSubsystem* net_ = nullptr;
  Endpoints endpoints_;
};

TEST_F(ClientTest, StreamingDiscoverDriveAndReadBack) {
  StreamClient c(endpoints_);
  const auto& robots = c.Discover(5000ms, {"arm"});
  const Robot& arm = robots.at("arm");
  EXPECT_EQ(arm.actuator_names, (std::vector<std::string>{"shoulder_motor", "elbow_motor"}));
  EXPECT_EQ(arm.ActuatorId("shoulder_motor"), arm.ActuatorId("arm_shoulder_motor"));
  EXPECT_THROW(arm.ActuatorId("knee"), std::out_of_range);
  EXPECT_THROW(c.SendControl("leg", {{"x", 1}}), std::out_of_range);
  const auto end = std::chrono::steady_clock::now() + 10s;
  double q = NAN;
  while (std::chrono::steady_clock::now() < end) {
    c.SendControl("arm", {{"shoulder_motor", 0.4}, {"elbow_motor", -0.2}});
    c.Poll(20ms);
    if (const auto j = c.Joint("arm", "shoulder")) q = j->qpos[0];
    if (std::abs(q - 0.4) < 0.05) break;
  }
  EXPECT_NEAR(q, 0.4, 0.05);
  const auto tip = c.Sensor("arm", "tip_pos");
  ASSERT_TRUE(tip);
  EXPECT_EQ(tip->size(), 3u);
}

TEST_F(ClientTest, LockstepThroughTheStepServer) {
  StepClient c(endpoints_.rpc);
  EXPECT_FALSE(c.session_id().empty());
  EXPECT_NE(c.hello_json().find("\"arm\""), std::string::npos);
  c.SetMode("direct");
  Observation o = c.Reset();
  const std::uint64_t step0 = o.step;
  for (int i = 1; i <= 200; ++i) {
    o = c.Step(5, {{"arm", {-0.4, 0.6}}});
    ASSERT_EQ(o.step, step0 + 5u * static_cast<std::uint64_t>(i));
  }
  ASSERT_EQ(o.per_articulation.at("arm").qpos.size(), 2u);
  EXPECT_NEAR(o.per_articulation.at("arm").qpos[1], 0.6, 0.05);
  EXPECT_EQ(o.per_articulation.at("arm").sensors.at("tip_pos").size(), 3u);
  try {
    c.Step(1, {{"arm", {1.0}}});
    FAIL() << "a control of the wrong size was accepted";
  } catch (const StepError& e) {
    EXPECT_EQ(e.code(), "dim_mismatch");
  }
  const std::string keys = c.Call("list_keyframes");
  EXPECT_NE(keys.find("arm_raised"), std::string::npos);
  EXPECT_THROW(c.Call("set_mode", R"({"mode": "warp"})"), StepError);
}

// The same lockstep rollout over a shared-memory channel and over ZeroMQ: the same states; the
// channel's file is gone once the client attached; a server that stops is an error for a client
// on the channel, not a hang.
TEST_F(ClientTest, LockstepOverSharedMemoryMatchesZeroMQ) {
  std::vector<std::vector<double>> runs[2];
  for (const bool shm : {true, false}) {
    StepClient c(endpoints_.rpc, "standard", 10000ms, shm);
    EXPECT_EQ(c.transport(), shm ? "shm" : "zmq");
    c.SetMode("direct");
    c.Reset();
    for (int i = 0; i < 100; ++i) {
      const Observation o = c.Step(2, {{"arm", {0.3 * std::sin(0.1 * i), -0.2}}});
      runs[shm ? 0 : 1].push_back(o.per_articulation.at("arm").qpos);
    }
  }
  EXPECT_EQ(runs[0], runs[1]);
  StepClient c(endpoints_.rpc);
  ASSERT_EQ(c.transport(), "shm");
  c.SetMode("direct");
  c.Step(1);
  manager_.EndPlay();
  EXPECT_THROW(c.Step(1), std::runtime_error);
}

TEST_F(ClientTest, PuppetAndContacts) {
  StepClient c(endpoints_.rpc, "full");
  c.SetMode("puppet");
  Observation o = c.Puppet({{"arm", {{0.25, -0.5}, {0.0, 0.0}, {}}}}, 2.5);
  EXPECT_EQ(o.time, 2.5);
  EXPECT_EQ(o.per_articulation.at("arm").qpos, (std::vector<double>{0.25, -0.5}));
  EXPECT_THROW(c.Puppet({{"arm", {{0.25}, {}, {}}}}), StepError);  // one value for two joints
  o = c.Puppet({{"arm", {{}, {}, {0.1, 0.2}}}});
  EXPECT_EQ(o.per_articulation.at("arm").qpos[1], -0.5);  // left as it was
  EXPECT_EQ(o.per_articulation.at("arm").ctrl, (std::vector<double>{0.1, 0.2}));
  bool truncated = true;
  const std::vector<Contact> contacts = c.Contacts(64, &truncated);
  EXPECT_FALSE(truncated);
  for (const Contact& k : contacts) EXPECT_FALSE(k.geom1.empty());
}

}  // namespace
}  // namespace urlab::client
