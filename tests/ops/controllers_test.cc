// Controllers (urlab/ops/controllers.h): PD gains from the {art}/set_gains topic, from the step
// server's configure_controller and from a direct call (the panel's and the CLI's path) are one
// operation: refused alike, and applied through the command frames, so a recording holds them
// (the applied commands' kp and kv of every step). Control source, twist and launchers too.
#include "urlab/ops/controllers.h"

#include <cmath>

#include "ops/ops_fixture.h"
#include "support/wait.h"
#include "urlab/replay/recording.h"
#include "urlab/wire/wire.h"

namespace urlab::ops::test {
namespace {

using urlab::testing::WaitFor;

TEST_F(OpsTest, GainsFromEveryPathGoThroughTheCommandFramesAndAreRecorded) {
  Play("direct", ", controller: {type: pd, kp: 10, kv: 1}", "", /*recorder=*/true);
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("recording_start", {{"path", "gains.urrec"}})["op"], "recording_start_ok");
  c.Op("step", {{"n_steps", 3}});

  // The topic: resent until the (late-joining) subscription takes it; the patch is idempotent.
  zmq::socket_t pub(ctx_, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.connect(net_->endpoints().control);
  const std::string topic = wire::SetGainsTopic("arm");
  ASSERT_TRUE(WaitFor([&] {
    pub.send(zmq::buffer(topic), zmq::send_flags::sndmore);
    pub.send(zmq::buffer(std::string(R"({"hinge": {"kp": 42}})")));
    return net_->counters().gains_applied > 0;
  }));
  c.Op("step", {{"n_steps", 3}});
  // The direct call (the panel's / CLI's path), then the step server's.
  SetGains(session(), "arm", {.named = {{"motor", {.kv = 3.0}}}});
  c.Op("step", {{"n_steps", 3}});
  const Json r = c.Op("configure_controller", {{"articulation", "arm"}, {"params", {{"kp", 7}}}});
  ASSERT_EQ(r["op"], "configure_controller_ok") << r.dump();
  EXPECT_EQ(r["params"]["gains"]["motor"],
            (Json{{"kp", 7.0}, {"kv", 3.0}, {"torque_limit", INFINITY}}));
  c.Op("step", {{"n_steps", 3}});
  ASSERT_EQ(c.Op("recording_stop")["op"], "recording_stop_ok");

  // Every gain change is in the recording, in order, from the step after it.
  const replay::RecordingReader reader = replay::RecordingReader::Open(dir_ + "/gains.urrec");
  std::vector<std::pair<double, double>> seen;  // distinct (kp, kv) overrides, in order
  for (const replay::Record& rec : replay::ReadAllRecords(reader)) {
    const auto* f = std::get_if<replay::Frame>(&rec);
    if (!f || f->commands.kp.empty()) continue;
    const std::pair<double, double> g{f->commands.kp[0], f->commands.kv[0]};
    const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    if (seen.empty() || !same(seen.back().first, g.first) || !same(seen.back().second, g.second)) {
      seen.push_back(g);
    }
  }
  ASSERT_GE(seen.size(), 3u);
  EXPECT_EQ(seen[seen.size() - 3].first, 42.0) << "the topic's kp is recorded";
  EXPECT_EQ(seen[seen.size() - 2], (std::pair<double, double>{42.0, 3.0}));
  EXPECT_EQ(seen.back(), (std::pair<double, double>{7.0, 3.0}));
}

TEST_F(OpsTest, GainRefusalsAreOneValidation) {
  Play("live", ", controller: {type: pd, kp: 10, kv: 1}");
  Client c(ctx_, rpc());
  c.Hello();
  // A name that reaches no actuator, a negative gain: the same code and message.
  EXPECT_EQ(
      FromReply(c.Op("configure_controller",
                     {{"articulation", "arm"}, {"params", {{"gains", {{"ghost", {{"kp", 1}}}}}}}})),
      FromCall([&] {
        SetGains(session(), "arm", {.named = {{"ghost", {.kp = 1.0}}}});
      }));
  EXPECT_EQ(
      FromReply(c.Op("configure_controller", {{"articulation", "arm"}, {"params", {{"kp", -1}}}})),
      FromCall([&] { SetGains(session(), "arm", {.all = {.kp = -1.0}}); }));
  EXPECT_EQ(
      FromReply(c.Op("configure_controller", {{"articulation", "leg"}, {"params", {{"kp", 1}}}})),
      FromCall([&] { SetGains(session(), "leg", {.all = {.kp = 1.0}}); }));
  EXPECT_EQ(Gains(session(), "arm")[0].kp, 10.0) << "nothing of a refused patch is applied";
  // The topic refuses the unknown name too (dropped and counted, the whole patch).
  zmq::socket_t pub(ctx_, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  pub.connect(net_->endpoints().control);
  ASSERT_TRUE(WaitFor([&] {
    pub.send(zmq::buffer(wire::SetGainsTopic("arm")), zmq::send_flags::sndmore);
    pub.send(zmq::buffer(std::string(R"({"hinge": {"kp": 99}, "ghost": {"kp": 1}})")));
    return net_->counters().drops[static_cast<std::size_t>(wire::Drop::kUnknownName)] > 0;
  }));
  EXPECT_EQ(Gains(session(), "arm")[0].kp, 10.0);
}

TEST_F(OpsTest, GainsNeedAPdController) {
  Play("live");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(
      FromReply(c.Op("configure_controller", {{"articulation", "arm"}, {"params", {{"kp", 1}}}})),
      FromCall([&] { SetGains(session(), "arm", {.all = {.kp = 1.0}}); }));
  EXPECT_EQ(FromCall([&] { Gains(session(), "arm"); }).code, "no_controller");
}

TEST_F(OpsTest, ControlSourceTwistAndLaunchersAreOneOperationEach) {
  Play("live");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(FromReply(c.Op("set_control_source", {{"source", "telepathy"}})),
            FromCall([&] { SetControlSource(session(), "telepathy"); }));
  EXPECT_EQ(FromReply(c.Op("set_control_source", {{"source", "ui"}, {"articulation", "leg"}})),
            FromCall([&] { SetControlSource(session(), "ui", "leg"); }));
  SetControlSource(session(), "ui", "arm");
  EXPECT_EQ(session().Require("arm").control->source_override(), control::ControlSource::kUi);
  ASSERT_EQ(c.Op("set_control_source", {{"source", "input"}})["op"], "set_control_source_ok");
  EXPECT_EQ(session().controls().global_source(), control::ControlSource::kInput);

  // The arm's free body gives it a twist controller: the same twist applied from either path.
  EXPECT_EQ(FromReply(c.Op("set_twist", {{"articulation", "leg"}})), FromCall([&] {
              SetTwist(session(), "leg", {1, 0, 0});
            }));
  const Json t = c.Op(
      "set_twist", {{"articulation", "arm"}, {"linear", {0.25, 0, 0}}, {"angular", {0, 0, 0.5}}});
  ASSERT_EQ(t["op"], "set_twist_ok") << t.dump();
  const control::Twist applied = SetTwist(session(), "arm", {0.25, 0, 0.5});
  EXPECT_EQ(t["linear"][0], applied.vx);
  EXPECT_EQ(t["angular"][2], applied.yaw_rate);
  EXPECT_EQ(FromCall([&] { SetTwist(session(), "arm", {std::nan(""), 0, 0}); }).code, "bad_value");
  EXPECT_EQ(FromReply(c.Op("fire_launcher", {{"launcher", "cannon"}})),
            FromCall([&] { FireLauncher(session(), "cannon"); }));
}

}  // namespace
}  // namespace urlab::ops::test
