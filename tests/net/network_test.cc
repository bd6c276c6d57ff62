// The network subsystem end to end over real ZeroMQ sockets on loopback (ephemeral ports, so
// parallel tests never collide): discovery, state topics, control applied as whole frames, gains,
// and a battery of malformed messages that are dropped, counted per reason, and change nothing.
#include "urlab/net/network.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "support/mujoco_test.h"
#include "support/wait.h"
#include "urlab/control/controllers.h"
#include "urlab/core/error.h"
#include "urlab/wire/wire.h"
#include "urlab/world/manager.h"

namespace urlab::net {
namespace {

using namespace std::chrono_literals;
using testing::WaitFor;

// An arm with a hinge, a ball joint, a floating box and a sensor; a second robot "b" shares
// actuator names (its ids must never be accepted on "a"'s topic).
constexpr const char* kRobotXml = R"(<mujoco model="robot">
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="wrist" pos="0.3 0 0">
        <joint name="ball" type="ball" damping="1"/>
        <geom type="sphere" size="0.05" mass="0.2"/>
      </body>
    </body>
    <body name="box" pos="1 0 0.5">
      <freejoint name="float"/>
      <geom type="box" size="0.05 0.05 0.05" mass="0.3"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="hinge_motor" joint="hinge" ctrlrange="-5 5" ctrllimited="true"/>
    <motor name="spare" joint="hinge"/>
  </actuator>
  <sensor>
    <jointpos name="hinge_pos" joint="hinge"/>
    <framequat name="wrist_quat" objtype="body" objname="wrist"/>
  </sensor>
</mujoco>
)";

class NetworkTest : public urlab::testing::MujocoTest {
 protected:
  void SetUp() override {
    dir_ = urlab::testing::MakeTempDir("network");
    urlab::testing::WriteTextFile(dir_, "robot.xml", kRobotXml);
  }
  // Plays two robots with passthrough control ("none") or PD, network on ephemeral ports.
  void Play(const std::string& controller = "{type: none}") {
    const std::string yaml =
        "control_source: network\narticulations:\n"
        "  - {name: a, mjcf: robot.xml, controller: " +
        controller +
        "}\n"
        "  - {name: b, mjcf: robot.xml, pos: [0, 2, 0], controller: " +
        controller + "}\n";
    NetworkOptions o;
    o.state = o.control = o.info = o.rpc = "tcp://127.0.0.1:*";
    auto net = std::make_unique<NetworkSubsystem>(o);
    net_ = net.get();
    world::ManagerOptions mo;
    mo.speed_percent = 100;
    manager_.AddSubsystem(std::move(net));
    manager_.BeginPlay(world::ParseScene(yaml, dir_ + "/scene.yaml"));
    ASSERT_FALSE(net_->endpoints().state.empty());
    ASSERT_FALSE(net_->endpoints().control.empty());
    ASSERT_FALSE(net_->endpoints().info.empty());
    state_.connect(net_->endpoints().state);
    state_.set(zmq::sockopt::subscribe, "");
    info_.connect(net_->endpoints().info);
    info_.set(zmq::sockopt::subscribe, "");
    control_.connect(net_->endpoints().control);
    std::this_thread::sleep_for(200ms);  // PUB/SUB joining (the slow-joiner)
  }
  // Receives state messages until `topic` arrives; its payload.
  std::string Receive(const std::string& topic, std::chrono::milliseconds timeout = 3000ms) {
    state_.set(zmq::sockopt::rcvtimeo, static_cast<int>(timeout.count()));
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      std::vector<zmq::message_t> parts;
      if (!zmq::recv_multipart(state_, std::back_inserter(parts))) break;
      if (parts.size() == 2 && parts[0].to_string() == topic) return parts[1].to_string();
    }
    return "";
  }
  void SendControl(const std::string& topic, const std::string& payload) {
    control_.send(zmq::buffer(topic), zmq::send_flags::sndmore);
    control_.send(zmq::buffer(payload));
  }
  int Actuator(const std::string& name) {
    return mj_name2id(manager_.session().engine().model(), mjOBJ_ACTUATOR, name.c_str());
  }
  double Ctrl(int id) {
    manager_.Tick();
    const physics::StateFrame* f = manager_.frame();
    return f ? f->ctrl[static_cast<std::size_t>(id)] : NAN;
  }
  std::uint64_t Drops(wire::Drop d) { return net_->counters().drops[static_cast<std::size_t>(d)]; }

  std::string dir_;
  world::Manager manager_;
  NetworkSubsystem* net_ = nullptr;
  zmq::context_t ctx_{1};
  zmq::socket_t state_{ctx_, zmq::socket_type::sub};
  zmq::socket_t info_{ctx_, zmq::socket_type::sub};
  zmq::socket_t control_{ctx_, zmq::socket_type::pub};
};

TEST_F(NetworkTest, DiscoveryListsEachRobotsOwnActuators) {
  Play();
  info_.set(zmq::sockopt::rcvtimeo, 3000);
  std::map<std::string, nlohmann::ordered_json> robots;
  while (robots.size() < 2) {
    zmq::message_t m;
    ASSERT_TRUE(info_.recv(m)) << "no discovery message within 3 s";
    const auto j = nlohmann::ordered_json::parse(m.to_string());
    robots[j["robot"]] = j;
  }
  const auto& a = robots["a"];
  std::vector<std::string> keys;
  for (const auto& [k, v] : a.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"type", "robot", "names", "ids", "mins", "maxs",
                                            "camera_list"}));
  EXPECT_EQ(a["type"], "actuator_list");
  EXPECT_EQ(a["names"], (std::vector<std::string>{"hinge_motor", "spare"}));  // short names
  EXPECT_EQ(a["ids"], (std::vector<int>{Actuator("a_hinge_motor"), Actuator("a_spare")}));
  EXPECT_EQ(a["mins"], (std::vector<double>{-5, -100}));
  EXPECT_EQ(a["maxs"], (std::vector<double>{5, 100}));
  EXPECT_EQ(robots["b"]["names"][0], "hinge_motor");
}

TEST_F(NetworkTest, StateTopicsCarryEveryJointKindAndSensors) {
  Play();
  const mjModel* m = manager_.session().engine().model();
  const auto hinge = wire::DecodeJoint(Receive("a/joint/hinge"));
  ASSERT_TRUE(hinge);
  EXPECT_EQ(hinge->joint_id, mj_name2id(m, mjOBJ_JOINT, "a_hinge"));
  const auto ball = wire::DecodeJoint(Receive("a/joint/ball"));
  ASSERT_TRUE(ball);
  EXPECT_EQ(ball->qpos.size(), 4u);
  EXPECT_NEAR(ball->qpos[0], 1.0f, 1e-6);  // identity quaternion, w first (as MuJoCo stores it)
  const auto base = wire::DecodeBaseState(Receive("a/base_state/float"));
  ASSERT_TRUE(base);
  EXPECT_NEAR(base->pos[0], 1.0f, 1e-5);
  EXPECT_NEAR(base->pos[2], 0.5f, 1e-5);
  EXPECT_NEAR(base->quat_wxyz[0], 1.0f, 1e-6);
  const auto b_base = wire::DecodeBaseState(Receive("b/base_state/float"));
  ASSERT_TRUE(b_base);
  EXPECT_NEAR(b_base->pos[1], 2.0f, 1e-5);  // b's placement
  const auto quat = wire::DecodeSensor(Receive("a/sensor/wrist_quat"));
  ASSERT_TRUE(quat);
  EXPECT_EQ(quat->values.size(), 4u);
  EXPECT_EQ(quat->sensor_id, mj_name2id(m, mjOBJ_SENSOR, "a_wrist_quat"));
}

// The state socket knows what subscribers asked for: a topic nobody wants is not sent at all.
TEST_F(NetworkTest, OnlySubscribedTopicsAreSent) {
  Play();
  // Sent per published step, measured over about 100 steps once subscriptions settled.
  const auto per_step = [&] {
    std::this_thread::sleep_for(300ms);  // the subscription change reaches the server
    const NetworkCounters before = net_->counters();
    EXPECT_TRUE(urlab::testing::WaitFor(
        [&] { return net_->counters().steps_published >= before.steps_published + 100; }));
    const NetworkCounters after = net_->counters();
    return static_cast<double>(after.state_messages - before.state_messages) /
           static_cast<double>(after.steps_published - before.steps_published);
  };
  const double everything = per_step();
  EXPECT_GE(everything, 10.0);  // two robots: joints, bases, sensors, state/full
  state_.set(zmq::sockopt::unsubscribe, "");
  state_.set(zmq::sockopt::subscribe, "a/joint/hinge");
  EXPECT_NEAR(per_step(), 1.0, 0.05);
  EXPECT_FALSE(Receive("a/joint/hinge").empty());
  state_.set(zmq::sockopt::unsubscribe, "a/joint/hinge");
  // No subscriber at all: the every-step ring is off, so nothing is even copied for the topics
  // while the simulation runs on.
  physics::PhysicsEngine& engine = manager_.session().engine();
  // The unsubscription reached the server once nothing more is published while the engine runs.
  EXPECT_TRUE(urlab::testing::WaitFor([&] {
    const std::uint64_t published = net_->counters().steps_published;
    const std::uint64_t at = engine.step_count();
    std::this_thread::sleep_for(50ms);
    return engine.step_count() > at && net_->counters().steps_published == published;
  }));
  const NetworkCounters idle = net_->counters();
  const std::uint64_t steps = engine.step_count();
  EXPECT_TRUE(urlab::testing::WaitFor([&] { return engine.step_count() >= steps + 100; }));
  EXPECT_EQ(net_->counters().state_messages, idle.state_messages);
  EXPECT_EQ(net_->counters().steps_published, idle.steps_published);
  state_.set(zmq::sockopt::subscribe, "a/");  // a prefix: every topic of robot a
  const double robot_a = per_step();
  EXPECT_GT(robot_a, 2.0);
  EXPECT_LT(robot_a, everything);
}

// The every-step ring is off without a subscriber: one who subscribes while the simulation is
// paused still gets its state (the engine publishes a frame when the ring comes on), and discovery
// goes on meanwhile on the engine's own counters.
TEST_F(NetworkTest, ASubscriberWhileNobodyListenedAndPausedGetsTheState) {
  Play();
  state_.set(zmq::sockopt::unsubscribe, "");
  physics::PhysicsEngine& engine = manager_.session().engine();
  std::this_thread::sleep_for(300ms);  // the unsubscription reaches the server: the ring is off
  engine.SetPaused(true);
  std::this_thread::sleep_for(100ms);
  const double time = manager_.session().engine().Snapshot().time;
  info_.set(zmq::sockopt::rcvtimeo, 3000);
  zmq::message_t m;
  EXPECT_TRUE(info_.recv(m)) << "no discovery while paused without state subscribers";
  // A new socket: the old one may still hold messages received before its unsubscription.
  zmq::socket_t late(ctx_, zmq::socket_type::sub);
  late.connect(net_->endpoints().state);
  late.set(zmq::sockopt::subscribe, "a/joint/hinge");
  late.set(zmq::sockopt::rcvtimeo, 3000);
  std::vector<zmq::message_t> parts;
  ASSERT_TRUE(zmq::recv_multipart(late, std::back_inserter(parts)))
      << "a late subscriber got no state while paused";
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].to_string(), "a/joint/hinge");
  EXPECT_TRUE(wire::DecodeJoint(parts[1].to_string()).has_value());
  EXPECT_EQ(engine.Snapshot().time, time);  // still paused: the frame is the paused state
}

TEST_F(NetworkTest, ControlIsAppliedWholeAndOnlyToItsOwnRobot) {
  Play();
  const int a0 = Actuator("a_hinge_motor"), a1 = Actuator("a_spare");
  const int b0 = Actuator("b_hinge_motor");
  std::string msg;
  const std::pair<std::int32_t, float> both[] = {{a0, 2.5f}, {a1, -1.5f}};
  wire::AppendControl(&msg, both);
  SendControl("a/control ", msg);
  ASSERT_TRUE(WaitFor([&] { return Ctrl(a0) == 2.5 && Ctrl(a1) == -1.5; }));
  EXPECT_EQ(Ctrl(b0), 0.0);
  EXPECT_EQ(net_->counters().controls_applied, 1u);
  // The hinge reads back its motion over the state topic.
  ASSERT_TRUE(WaitFor([&] {
    const auto j = wire::DecodeJoint(Receive("a/joint/hinge"));
    return j && j->qvel[0] > 0.1f;
  }));
}

// Crafted payloads: every one dropped as a whole, counted under its reason, nothing applied,
// and the process keeps running.
TEST_F(NetworkTest, MalformedControlIsDroppedCountedAndChangesNothing) {
  Play("{type: pd, kp: 10, kv: 1}");
  const int a0 = Actuator("a_hinge_motor"), b0 = Actuator("b_hinge_motor");
  const auto control = [](std::vector<std::pair<std::int32_t, float>> v) {
    std::string s;
    wire::AppendControl(&s, v);
    return s;
  };
  std::string truncated = control({{a0, 1}});
  truncated.pop_back();
  std::string negative(4, '\xff');
  std::string huge = "\xff\xff\xff\x7f";
  struct Case {
    std::string topic, payload;
    wire::Drop reason;
  };
  const std::vector<Case> cases = {
      {"a/control ", truncated, wire::Drop::kTruncated},
      {"a/control ", control({{a0, 1}}) + "x", wire::Drop::kBadSize},
      {"a/control ", negative, wire::Drop::kNegativeCount},
      {"a/control ", huge, wire::Drop::kTooMany},
      {"a/control ", control({{a0, 1}, {a0, 1}, {a0, 1}}), wire::Drop::kTooMany},
      {"a/control ", control({{a0, 1}, {b0, 1}}), wire::Drop::kForeignActuator},  // b's id
      {"a/control ", control({{a0, 1}, {99999, 1}}), wire::Drop::kForeignActuator},
      {"a/control ", control({{a0, NAN}}), wire::Drop::kNonFinite},
      {"a/control", control({{a0, 1}}), wire::Drop::kUnknownTopic},  // no trailing space
      {"ab/control ", control({{a0, 1}}), wire::Drop::kUnknownTopic},
      {"a/set_gains ", "{\"hinge\": {\"kp\": ", wire::Drop::kBadJson},
      {"a/set_gains ", R"({"nope": {"kp": 1}})", wire::Drop::kUnknownName},
      {"a/set_gains ", R"({"hinge": {"kp": -1}})", wire::Drop::kBadNumber},
      {"a/set_gains ", R"({"hinge": {"kd": 1}})", wire::Drop::kUnknownField},
      // Limits: deeper than set_gains' shape, larger than any control message.
      {"a/set_gains ", R"({"hinge": {"kp": {"x": 1}}})", wire::Drop::kBadJson},
      {"a/control ", std::string(wire::kMaxInboundPayloadBytes + 1, '\0'), wire::Drop::kTooLarge},
      // One bad name spoils the whole patch: the good one is not applied either.
      {"a/set_gains ", R"({"hinge": {"kp": 777}, "nope": {"kp": 1}})", wire::Drop::kUnknownName},
  };
  for (const Case& c : cases) SendControl(c.topic, c.payload);
  control_.send(zmq::buffer("a/control "), zmq::send_flags::none);  // one frame only
  ASSERT_TRUE(WaitFor([&] { return net_->counters().total_drops() == cases.size() + 1; }))
      << net_->counters().total_drops();
  std::map<wire::Drop, std::uint64_t> expected;
  for (const Case& c : cases) ++expected[c.reason];
  ++expected[wire::Drop::kBadFraming];
  for (const auto& [reason, n] : expected) EXPECT_EQ(Drops(reason), n) << wire::DropName(reason);
  EXPECT_EQ(net_->counters().controls_applied, 0u);
  EXPECT_EQ(net_->counters().gains_applied, 0u);
  auto* pd = dynamic_cast<control::PdController*>(
      manager_.session().FindArticulation("a")->control->controller());
  ASSERT_NE(pd, nullptr);
  EXPECT_EQ(pd->gains(0).kp, 10.0);
  EXPECT_EQ(manager_.session().FindArticulation("a")->control->GetTarget(
                control::ControlSource::kNetwork, 0),
            0.0);
  // Still serving: a good gain patch by joint name, then by prefixed actuator name.
  SendControl("a/set_gains ", R"({"hinge": {"kp": 50}, "a_spare": {"kv": 3}})");
  ASSERT_TRUE(WaitFor([&] { return net_->counters().gains_applied == 1; }));
  EXPECT_EQ(pd->gains(0).kp, 50.0);
  EXPECT_EQ(pd->gains(0).kv, 1.0);  // not mentioned: unchanged
  EXPECT_EQ(pd->gains(1).kv, 3.0);
}

TEST_F(NetworkTest, PortInUseIsReportedAndTheSimulationRuns) {
  zmq::context_t ctx(1);
  zmq::socket_t squatter(ctx, zmq::socket_type::pub);
  squatter.bind("tcp://127.0.0.1:*");
  const std::string taken = squatter.get(zmq::sockopt::last_endpoint);
  NetworkOptions o;
  o.state = taken;  // already bound by this process
  o.control = o.info = o.rpc = "tcp://127.0.0.1:*";
  world::Manager m;
  auto* net =
      &static_cast<NetworkSubsystem&>(m.AddSubsystem(std::make_unique<NetworkSubsystem>(o)));
  m.BeginPlay(
      world::ParseScene("articulations:\n  - {name: a, mjcf: robot.xml}\n", dir_ + "/scene.yaml"));
  EXPECT_EQ(net->endpoints().state, "");
  EXPECT_FALSE(net->endpoints().control.empty());
  const std::uint64_t before = m.session().engine().step_count();
  ASSERT_TRUE(WaitFor([&] { return m.session().engine().step_count() > before + 50; }));
  m.EndPlay();
}

// require_bind (a headless `urlab run`): BeginPlay throws before the physics starts, naming the
// port, the socket and the process holding it (this one); nothing is left playing.
TEST_F(NetworkTest, ATakenPortStopsBeginPlayWhenTheNetworkIsRequired) {
  zmq::context_t ctx(1);
  zmq::socket_t squatter(ctx, zmq::socket_type::router);
  squatter.bind("tcp://127.0.0.1:*");
  const std::string taken = squatter.get(zmq::sockopt::last_endpoint);
  const std::string port = taken.substr(taken.rfind(':') + 1);
  NetworkOptions o;
  o.state = o.control = o.info = "tcp://127.0.0.1:*";
  o.rpc = taken;
  o.require_bind = true;
  world::Manager m;
  m.AddSubsystem(std::make_unique<NetworkSubsystem>(o));
  try {
    m.BeginPlay(world::ParseScene("articulations:\n  - {name: a, mjcf: robot.xml}\n",
                                  dir_ + "/scene.yaml"));
    FAIL() << "BeginPlay went on with port " << port << " taken";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("port " + port + " (step server) is in use by pid " +
                        std::to_string(::getpid()) + " ("),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("--allow-no-network"), std::string::npos) << what;
  }
  EXPECT_FALSE(m.playing());
}

}  // namespace
}  // namespace urlab::net
