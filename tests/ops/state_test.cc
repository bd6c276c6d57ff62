// State edits (urlab/ops/state.h): joint positions, mocap poses and physics options through the
// step server and directly (the viewer's physics options call ops::SetOptions): the same
// refusals, nothing applied by a refused request, the same state from the same request.
#include "urlab/ops/state.h"

#include "ops/ops_fixture.h"

namespace urlab::ops::test {
namespace {

TEST_F(OpsTest, SetQposRefusesAlikeOnEveryPath) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello({{"observations", "minimal"}});
  struct Case {
    const char* articulation;
    std::vector<double> qpos;
    const char* code;
  };
  const Case cases[] = {
      {"arm", {1, 2}, "dim_mismatch"},
      {"arm", {1e9, 0, 0, 0.049, 1, 0, 0, 0}, "bad_value"},
      {"arm", {0, 0, 0.1, 0, 0, 0, 0}, "bad_value"},  // the free base's zero quaternion
      {"leg", {0}, "unknown_articulation"},
  };
  const Json before = c.Op("forward");
  for (const Case& k : cases) {
    const Refusal wire =
        FromReply(c.Op("set_qpos", {{"articulation", k.articulation}, {"qpos", k.qpos}}));
    EXPECT_EQ(wire.code, k.code);
    EXPECT_EQ(wire, FromCall([&] { SetQpos(session(), k.articulation, k.qpos); }));
  }
  EXPECT_EQ(c.Op("forward")["per_articulation"], before["per_articulation"]);
  // The free base alone (7 values) or every joint, from either path.
  Json r = c.Op("set_qpos", {{"articulation", "arm"}, {"qpos", {0.1, 0, 0, 0.5, 1, 0, 0, 0}}});
  ASSERT_EQ(r["op"], "set_qpos_ok") << r.dump();
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][3], 0.5);
  Wait(SetQpos(session(), "arm", {1, 0, 0.3, 1, 0, 0, 0}));
  r = c.Op("forward");
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], 0.1) << "the hinge kept its value";
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][1], 1.0);
}

TEST_F(OpsTest, MocapPosesRefuseAlikeOnEveryPath) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(FromReply(c.Op("set_mocap_pose", {{"body", "ghost"}, {"pos", {0, 0, 0}}})),
            FromCall([&] {
              SetMocapPose(session(), "ghost", {0, 0, 0}, {1, 0, 0, 0});
            }));
  EXPECT_EQ(FromReply(c.Op("set_mocap_pose", {{"body", "arm_link"}, {"pos", {0, 0, 0}}})),
            FromCall([&] {
              SetMocapPose(session(), "arm_link", {0, 0, 0}, {1, 0, 0, 0});
            }));
  const Refusal norm =
      FromReply(c.Op("set_mocap_pose", {{"body", "arm_target"}, {"quat", {2, 0, 0, 0}}}));
  EXPECT_EQ(norm.code, "bad_value");
  EXPECT_EQ(norm, FromCall([&] {
              SetMocapPose(session(), "arm_target", {0, 0, 2}, {2, 0, 0, 0});
            }));
  EXPECT_EQ(FromReply(c.Op("set_mocap_pose", {{"body", "arm_target"}, {"pos", {0, 0, 1e9}}})),
            FromCall([&] {
              SetMocapPose(session(), "arm_target", {0, 0, 1e9}, {1, 0, 0, 0});
            }));
  Wait(SetMocapPose(session(), "arm_target", {1, 2, 3}, {1, 0, 0, 0}));
  EXPECT_EQ(c.Op("read_mocap_pose", {{"body", "arm_target"}})["pos"], Json::array({1.0, 2.0, 3.0}));
  EXPECT_EQ(MocapIndex(session(), "arm_target"), 0);
}

TEST_F(OpsTest, OptionsRefuseAlikeAndApplyTheSame) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(FromReply(c.Op("set_sim_options", {{"options", {{"timestep", -1}}}})),
            FromCall([&] { SetOptions(session(), {.timestep = -1.0}); }));
  EXPECT_EQ(FromReply(c.Op("set_sim_options", {{"options", {{"iterations", 0}}}})),
            FromCall([&] { SetOptions(session(), {.iterations = 0}); }));
  EXPECT_EQ(FromReply(c.Op("set_sim_options", {{"options", {{"gravity", {0, 0, 1e9}}}}})),
            FromCall([&] {
              SetOptions(session(), {.gravity = std::array<double, 3>{0, 0, 1e9}});
            }));
  EXPECT_EQ(FromCall([&] { SetOptions(session(), {.solver = 7}); }).code, "bad_value");
  EXPECT_EQ(session().engine().timestep(), 0.002) << "nothing of a refused change is applied";
  const OptionsSet set = SetOptions(session(), {.timestep = 0.001, .integrator = mjINT_RK4});
  Wait(set.seq);
  EXPECT_EQ(set.options->timestep, 0.001);
  const Json r = c.Op("set_sim_options", {{"options", {{"solver", "CG"}}}});
  EXPECT_EQ(r["options"]["timestep"], 0.001);
  EXPECT_EQ(r["options"]["integrator"], mjINT_RK4);
  EXPECT_EQ(r["options"]["solver"], mjSOL_CG);
}

}  // namespace
}  // namespace urlab::ops::test
