// Targets (urlab/ops/targets.h): the step server's step (ctrl, ctrl_map, xfrc_applied), the
// {art}/control topic and a direct call (the viewer's sliders and input mapping make it, on their
// own control source) are one operation: the same targets in the same frame channel, the same
// forces, and the same refusals (the topic, which has no reply, counts them by reason).
#include "urlab/ops/targets.h"

#include <cmath>
#include <limits>

#include "ops/ops_fixture.h"
#include "support/wait.h"
#include "urlab/ops/simulation.h"
#include "urlab/wire/wire.h"

namespace urlab::ops::test {
namespace {

using control::ControlSource;
using urlab::testing::WaitFor;

// One {art}/control message: {actuator id, value} pairs.
std::string ControlPayload(const std::vector<std::pair<std::int32_t, float>>& values) {
  std::string out;
  const auto put = [&out](const void* p) { out.append(static_cast<const char*>(p), 4); };
  const auto n = static_cast<std::int32_t>(values.size());
  put(&n);
  for (const auto& [id, v] : values) {
    put(&id);
    put(&v);
  }
  return out;
}

class TargetsTest : public OpsTest {
 protected:
  double Target(ControlSource source) {
    return manager_.session().Require("arm").control->GetTarget(source, 0);
  }
  std::uint64_t Drops(wire::Drop d) const {
    return net_->counters().drops[static_cast<std::size_t>(d)];
  }
  // Sends `values` on arm's control topic until the network counted `done` (a late-joining
  // subscription misses the first messages; a control patch is idempotent).
  bool SendControl(const std::vector<std::pair<std::int32_t, float>>& values,
                   const std::function<bool()>& done) {
    if (!pub_) {
      pub_.emplace(ctx_, zmq::socket_type::pub);
      pub_->set(zmq::sockopt::linger, 0);
      pub_->connect(net_->endpoints().control);
    }
    const std::string topic = wire::ControlTopic("arm"), payload = ControlPayload(values);
    return WaitFor([&] {
      pub_->send(zmq::buffer(topic), zmq::send_flags::sndmore);
      pub_->send(zmq::buffer(payload));
      return done();
    });
  }
  std::optional<zmq::socket_t> pub_;
};

TEST_F(TargetsTest, EveryPathSetsTheSameTargetsThroughOneOperation) {
  Play("live");
  Client c(ctx_, rpc());
  c.Hello();
  // The step server: by order, then by actuator and by joint name.
  ASSERT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl", {0.25}}}}}}})["op"], "step_ok");
  EXPECT_EQ(Target(ControlSource::kNetwork), 0.25);
  ASSERT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl_map", {{"motor", 0.5}}}}}}}})["op"],
            "step_ok");
  EXPECT_EQ(Target(ControlSource::kNetwork), 0.5);
  ASSERT_EQ(
      c.Op("step", {{"per_articulation", {{"arm", {{"ctrl_map", {{"hinge", 0.75}}}}}}}})["op"],
      "step_ok");
  EXPECT_EQ(Target(ControlSource::kNetwork), 0.75);
  // The topic, by the actuator's model id.
  const int motor = mj_name2id(session().engine().model(), mjOBJ_ACTUATOR, "arm_motor");
  ASSERT_GE(motor, 0);
  ASSERT_TRUE(SendControl({{motor, 1.5f}}, [&] { return Target(ControlSource::kNetwork) == 1.5; }));
  // The direct call the panel's sliders make: their own source, the network's untouched.
  SetTargets(session(), {.source = ControlSource::kUi,
                         .articulations = {{.articulation = "arm", .by_id = {{motor, -0.5}}}}});
  EXPECT_EQ(Target(ControlSource::kUi), -0.5);
  EXPECT_EQ(Target(ControlSource::kNetwork), 1.5);
  SetTargets(session(),
             {.articulations = {{.articulation = "arm", .by_name = {{"arm_hinge", 2}}}}});
  EXPECT_EQ(Target(ControlSource::kNetwork), 2.0);
}

TEST_F(TargetsTest, RefusalsAreOneValidationOnEveryPath) {
  Play("live");
  Client c(ctx_, rpc());
  c.Hello();
  const auto step = [&](Json entry) {
    return FromReply(c.Op("step", {{"per_articulation", {{"arm", std::move(entry)}}}}));
  };
  const auto call = [&](ArticulationTargets t) {
    return FromCall([&] {
      t.articulation = t.articulation.empty() ? "arm" : t.articulation;
      SetTargets(session(), {.source = ControlSource::kUi, .articulations = {std::move(t)}});
    });
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<Refusal, Refusal>> cases = {
      // out of range, NaN and infinity (msgpack carries them): the range's message, named
      {step({{"ctrl", {1e12}}}), call({.ctrl = std::vector{1e12}})},
      {step({{"ctrl", {nan}}}), call({.ctrl = std::vector{nan}})},
      {step({{"ctrl_map", {{"motor", -INFINITY}}}}), call({.by_name = {{"motor", -INFINITY}}})},
      {step({{"xfrc_applied", {{"ball", {0, 0, 1e10, 0, 0, 0}}}}}),
       call({.wrenches = {{"ball", {0, 0, 1e10, 0, 0, 0}}}})},
      // names and counts
      {step({{"ctrl_map", {{"ghost", 1}}}}), call({.by_name = {{"ghost", 1}}})},
      {step({{"ctrl", {1, 2}}}), call({.ctrl = std::vector<double>{1, 2}})},
      {step({{"xfrc_applied", {{"ghost", {0, 0, 1, 0, 0, 0}}}}}),
       call({.wrenches = {{"ghost", {0, 0, 1, 0, 0, 0}}}})},
      {step({{"xfrc_applied", {{"arm_ball", {0, 0, 1}}}}}),
       call({.wrenches = {{"arm_ball", {0, 0, 1}}}})},
  };
  for (const auto& [server, direct] : cases) {
    EXPECT_NE(server.code, "(no error)") << server;
    EXPECT_EQ(server, direct);
  }
  EXPECT_EQ(cases[0].first.message, "arm: ctrl must be in [-1e+09, 1e+09], got 1e+12");
  EXPECT_EQ(cases[1].first.message, "arm: ctrl must be in [-1e+09, 1e+09], got nan");
  EXPECT_EQ(cases[4].first.code, "bad_value");
  EXPECT_EQ(cases[5].first.code, "dim_mismatch");
  EXPECT_EQ(cases[6].first.code, "unknown_body");
  EXPECT_EQ(FromReply(c.Op("step", {{"per_articulation", {{"leg", {{"ctrl", {1}}}}}}})),
            call({.articulation = "leg", .ctrl = std::vector<double>{1}}));
  // A request is refused whole: a good articulation entry beside a bad value changes nothing.
  EXPECT_EQ(call({.ctrl = std::vector{0.5}, .by_name = {{"motor", 1e12}}}).code, "bad_value");
  EXPECT_EQ(Target(ControlSource::kUi), 0.0);
  EXPECT_EQ(Target(ControlSource::kNetwork), 0.0);

  // The topic: the same checks, counted by reason (and nothing applied).
  const int motor = mj_name2id(session().engine().model(), mjOBJ_ACTUATOR, "arm_motor");
  ASSERT_TRUE(SendControl({{motor, 1e10f}}, [&] { return Drops(wire::Drop::kBadNumber) > 0; }));
  EXPECT_EQ(FromCall([&] {
              SetTargets(session(),
                         {.articulations = {{.articulation = "arm", .by_id = {{motor, 1e10}}}}});
            }).message,
            "arm: ctrl must be in [-1e+09, 1e+09], got 1e+10");
  ASSERT_TRUE(
      SendControl({{motor + 7, 1.0f}}, [&] { return Drops(wire::Drop::kForeignActuator) > 0; }));
  EXPECT_EQ(FromCall([&] {
              SetTargets(session(),
                         {.articulations = {{.articulation = "arm", .by_id = {{motor + 7, 1}}}}});
            }),
            (Refusal{"bad_value", "arm: actuator " + std::to_string(motor + 7) +
                                      " is not one of this articulation"}));
  ASSERT_TRUE(SendControl({{motor, 0.5f}, {motor, 0.25f}},
                          [&] { return Drops(wire::Drop::kTooMany) > 0; }));
  EXPECT_EQ(FromCall([&] {
              SetTargets(session(), {.articulations = {{.articulation = "arm",
                                                        .by_id = {{motor, 0.5}, {motor, 0.25}}}}});
            }).code,
            "dim_mismatch");
  EXPECT_EQ(net_->counters().controls_applied, 0u);
  EXPECT_EQ(Target(ControlSource::kNetwork), 0.0);
}

TEST_F(TargetsTest, ForcesFromTheStepServerAndADirectCallAreTheSameCommands) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("reset")["op"], "reset_ok");
  const Json wrench = {0.5, 0, 0, 0, 0, 0.01};
  const Json pushed = c.Op(
      "step",
      {{"n_steps", 20}, {"per_articulation", {{"arm", {{"xfrc_applied", {{"ball", wrench}}}}}}}});
  ASSERT_EQ(pushed["op"], "step_ok") << pushed.dump();
  ASSERT_EQ(c.Op("reset")["op"], "reset_ok");
  SetTargets(session(), {.articulations = {{.articulation = "arm",
                                            .wrenches = {{"arm_ball", {0.5, 0, 0, 0, 0, 0.01}}}}},
                         .force_steps = 20});
  const Json direct = c.Op("step", {{"n_steps", 20}});
  ASSERT_EQ(direct["op"], "step_ok") << direct.dump();
  EXPECT_EQ(direct["time"], pushed["time"]);
  EXPECT_EQ(direct["per_articulation"]["arm"]["qpos"], pushed["per_articulation"]["arm"]["qpos"]);
  EXPECT_GT(pushed["per_articulation"]["arm"]["qpos"][1].get<double>(), 0.5) << "the ball moved";
}

}  // namespace
}  // namespace urlab::ops::test
