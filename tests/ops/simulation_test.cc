// Simulation control (urlab/ops/simulation.h): reset, pause, speed and lockstep steps reached
// through the step server and directly (the viewer's Reset/Pause/Step/speed controls and
// `urlab run`'s SIGUSR1 pause and auto-reset call these functions); each refusal is the same code
// and message on every path, and a refused request changes nothing.
#include "urlab/ops/simulation.h"

#include "ops/ops_fixture.h"

namespace urlab::ops::test {
namespace {

TEST_F(OpsTest, ResetTakesTheSameRequestsAndRefusalsOnEveryPath) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello({{"observations", "minimal"}});
  c.Op("step", {{"n_steps", 3}});
  const double t = c.Op("forward")["time"];
  ASSERT_GT(t, 0.0);

  // Bad requests, as the wire says them and as the typed request says them.
  struct Case {
    Json fields;
    ResetRequest request;
    const char* code;
  };
  const Case cases[] = {
      {{{"keyframe_name", "nope"}}, {.keyframe = "nope"}, "unknown_keyframe"},
      {{{"per_articulation_qpos", {{"leg", {{"hinge", 1}}}}}},
       {.joints = {{"leg", "hinge", {1}}}},
       "unknown_articulation"},
      {{{"per_articulation_qpos", {{"arm", {{"ghost", 1}}}}}},
       {.joints = {{"arm", "ghost", {1}}}},
       "bad_value"},
      {{{"per_articulation_qpos", {{"arm", {{"hinge", {1, 2}}}}}}},
       {.joints = {{"arm", "hinge", {1, 2}}}},
       "dim_mismatch"},
      {{{"per_articulation_qpos", {{"arm", {{"hinge", 1e9}}}}}},
       {.joints = {{"arm", "hinge", {1e9}}}},
       "bad_value"},
      {{{"per_articulation_qpos", {{"arm", {{"ball_free", {0, 0, 1, 0, 0, 0, 0}}}}}}},
       {.joints = {{"arm", "ball_free", {0, 0, 1, 0, 0, 0, 0}}}},
       "bad_value"},  // a zero quaternion
  };
  for (const Case& k : cases) {
    const Refusal wire = FromReply(c.Op("reset", k.fields));
    const Refusal direct = FromCall([&] { Reset(session(), k.request); });
    EXPECT_EQ(wire.code, k.code) << k.fields.dump();
    EXPECT_EQ(wire, direct) << k.fields.dump();
  }
  EXPECT_EQ(c.Op("forward")["time"], t) << "a refused reset resets nothing";

  // The same good request: the same state.
  Json r = c.Op("reset", {{"keyframe_name", "bent"},
                          {"per_articulation_qpos", {{"arm", {{"hinge", -0.25}}}}}});
  ASSERT_EQ(r["op"], "reset_ok") << r.dump();
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], -0.25);
  EXPECT_EQ(r["time"], 0.0);
  c.Op("step", {{"n_steps", 2}});
  Wait(Reset(session(), {.keyframe = "bent", .joints = {{"arm", "hinge", {-0.25}}}}));
  r = c.Op("forward");
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], -0.25);
  EXPECT_EQ(r["time"], 0.0);
  // The initial state (the viewer's R, `urlab run`'s reset after a divergence).
  c.Op("step", {{"n_steps", 2}});
  Wait(Reset(session(), {}));
  EXPECT_EQ(c.Op("forward")["time"], 0.0);

  // One articulation's keyframe (the panel's keyframe Reset).
  Wait(ResetArticulation(session(), "arm", "bent"));
  EXPECT_DOUBLE_EQ(c.Op("forward")["per_articulation"]["arm"]["qpos"][0], 0.7);
  EXPECT_EQ(FromCall([&] { ResetArticulation(session(), "leg", "bent"); }).code,
            "unknown_articulation");
  EXPECT_EQ(FromCall([&] { ResetArticulation(session(), "arm", "nope"); }).code,
            "unknown_keyframe");
}

TEST_F(OpsTest, PauseSpeedAndStepsAreOneOperationEach) {
  Play("live");
  Client c(ctx_, rpc());
  c.Hello();
  physics::PhysicsEngine& engine = session().engine();
  ASSERT_EQ(c.Op("set_paused", {{"paused", true}})["paused"], true);
  EXPECT_TRUE(engine.paused());
  Wait(SetPaused(session(), false));
  EXPECT_FALSE(engine.paused());
  Wait(SetPaused(session(), true));
  EXPECT_TRUE(engine.paused());
  // At once (the viewer's P, urlab run's SIGUSR1): no command to wait for.
  EXPECT_EQ(SetPaused(session(), false, When::kNow), 0u);
  EXPECT_FALSE(engine.paused());
  EXPECT_EQ(SetPaused(session(), true, When::kNow), 0u);
  EXPECT_TRUE(engine.paused());

  // Speed: clamped to 5..100 whoever asks; a non-finite one refused alike.
  EXPECT_EQ(c.Op("set_sim_speed", {{"percent", 500}})["percent"], 100);
  EXPECT_EQ(SetSpeed(session(), 3), 5);
  EXPECT_EQ(engine.speed_percent(), 5);
  EXPECT_EQ(c.Op("set_sim_speed", {{"percent", 49.6}})["percent"], 50);
  EXPECT_EQ(SetSpeed(session(), 49.6), 50);
  EXPECT_EQ(FromCall([&] { SetSpeed(session(), std::nan("")); }).code, "bad_value");

  // Steps: a window of n while paused; n out of range refused with one message.
  const std::uint64_t before = engine.step_count();
  Wait(Step(session(), 3));
  EXPECT_EQ(engine.step_count(), before + 3);
  ASSERT_EQ(c.Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  for (int n : {0, -5, 200000}) {
    EXPECT_EQ(FromReply(c.Op("step", {{"n_steps", n}})), FromCall([&] { Step(session(), n); }))
        << n;
  }
  EXPECT_EQ(engine.step_count(), before + 3);
  Wait(Forward(session()));  // the step server's forward: no step
  EXPECT_EQ(engine.step_count(), before + 3);
}

}  // namespace
}  // namespace urlab::ops::test
