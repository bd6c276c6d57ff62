// The step server, driven by a client written only from docs/protocol.md's tables: raw ZeroMQ REQ
// and DEALER sockets and msgpack/JSON encoded here with nlohmann (none of the project's client
// code). Real sockets on loopback with ephemeral ports.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"
#include "support/wait.h"
#include "urlab/wire/wire.h"

// A namespace of their own: their plain nlohmann::json alias must not meet net::Json (the
// ordered one) where a unity build puts several test files in one translation unit.
namespace urlab::net::tests {
namespace {

using namespace std::chrono_literals;
using Json = nlohmann::json;

constexpr const char* kArmXml = R"(<mujoco model="arm">
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
    <body name="target" mocap="true" pos="0 0 2">
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
  <keyframe>
    <key name="bent" qpos="0.7"/>
  </keyframe>
</mujoco>
)";

using test_client::Client;

class StepServerTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override { urlab::testing::WriteTextFile(dir_, "arm.xml", kArmXml); }
  void Play(std::chrono::milliseconds lease = 5000ms, const std::string& mode = "live",
            const std::string& controller = "", const std::string& mjcf = "arm.xml") {
    NetworkOptions o = urlab::testing::AutoPorts(mode);
    o.lease_timeout = lease;
    Serve("control_source: network\narticulations:\n  - {name: arm, mjcf: " + mjcf + controller +
              "}\n",
          o);
  }
};

TEST_F(StepServerTest, HelloDescribesTheSceneAndMetaListsTheOperations) {
  Play();
  Client c(ctx_, rpc());
  const Json h = c.Hello({{"seq", 7}});
  ASSERT_EQ(h["op"], "hello_ok") << h.dump();
  EXPECT_EQ(h["seq"], 7);
  EXPECT_EQ(h["protocol_version"], 1);
  EXPECT_EQ(h["mujoco_version_int"], mj_version());
  EXPECT_FALSE(c.session().empty());
  EXPECT_TRUE(h["mjb"].is_binary());
  EXPECT_EQ(h["mjb"].get_binary().size(),
            static_cast<std::size_t>(mj_sizeModel(manager_.session().engine().model())));
  const Json& arm = h["articulations"][0];
  EXPECT_EQ(arm["name"], "arm");
  EXPECT_EQ(arm["prefix"], "arm_");
  EXPECT_EQ(arm["default_control_mode"], "raw");
  EXPECT_EQ(arm["joints"][0]["name"], "hinge");
  EXPECT_EQ(arm["joints"][0]["type"], "hinge");
  EXPECT_EQ(arm["actuators"][0]["name"], "motor");  // short, like joints and sensors
  EXPECT_TRUE(arm["actuators"][0].contains("target_range"));
  EXPECT_EQ(arm["sensors"][0]["name"], "angle");
  const Json meta = c.Call({{"op", "meta"}});
  ASSERT_EQ(meta["op"], "meta_ok");
  std::vector<std::string> ops;
  for (const Json& o : meta["operations"]) ops.push_back(o["name"]);
  for (const char* op : {"hello", "step", "reset", "set_mode", "set_qpos", "set_mocap_pose",
                         "read_mocap_pose", "list_keyframes", "set_sim_options", "bye"}) {
    EXPECT_NE(std::find(ops.begin(), ops.end(), op), ops.end()) << op;
  }
}

// Lockstep: in direct mode each step request runs exactly n iterations with the given controls,
// and the reply shows the state after them; the streaming topics keep publishing.
TEST_F(StepServerTest, DirectModeStepsExactlyAndTheStreamingTopicsGoOn) {
  Play();
  zmq::socket_t sub(ctx_, zmq::socket_type::sub);
  sub.set(zmq::sockopt::subscribe, "arm/joint/hinge");
  sub.set(zmq::sockopt::rcvtimeo, 3000);
  sub.connect(net_->endpoints().state);
  Client c(ctx_, rpc());
  c.Hello({{"observations", "full"}});
  const Json mode = c.Op("set_mode", {{"mode", "direct"}});
  ASSERT_EQ(mode["op"], "set_mode_ok") << mode.dump();
  EXPECT_EQ(mode["previous_mode"], "live");
  EXPECT_EQ(mode["current_mode"], "direct");
  Json r = c.Op("step", {{"n_steps", 1}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  std::uint64_t step = r["step"];
  double last_qvel = 0;
  for (int i = 0; i < 20; ++i) {
    r = c.Op("step",
             {{"n_steps", 10}, {"seq", i}, {"per_articulation", {{"arm", {{"ctrl", {2.0}}}}}}});
    ASSERT_EQ(r["op"], "step_ok") << r.dump();
    EXPECT_EQ(r["seq"], i);
    EXPECT_EQ(r["step"].get<std::uint64_t>(), step + 10);  // exactly n iterations
    step = r["step"];
    EXPECT_NEAR(r["time"].get<double>(), static_cast<double>(step) * 0.002, 1e-9);
    const Json& arm = r["per_articulation"]["arm"];
    EXPECT_EQ(arm["ctrl"][0], 2.0);
    EXPECT_GT(arm["qvel"][0].get<double>(), last_qvel);  // the motor accelerates the hinge
    last_qvel = arm["qvel"][0];
    // Sensors are MuJoCo's from the start of the last step (before integration).
    EXPECT_LT(arm["sensors"]["angle"][0].get<double>(), arm["qpos"][0].get<double>());
    EXPECT_NEAR(arm["sensors"]["angle"][0].get<double>(), arm["qpos"][0].get<double>(), 0.02);
    EXPECT_EQ(arm["xpos"]["link"].size(), 3u);
    EXPECT_EQ(arm["actuator_force"][0], 2.0);
  }
  // Paused between requests: no steps without a request.
  std::this_thread::sleep_for(30ms);
  EXPECT_EQ(manager_.session().engine().step_count(), step);
  std::vector<zmq::message_t> parts;  // the topics were published for the stepped states
  ASSERT_TRUE(zmq::recv_multipart(sub, std::back_inserter(parts)));
  EXPECT_EQ(parts[1].size(), wire::kJointBytes);
  // Back to live: the loop runs on its own.
  ASSERT_EQ(c.Op("set_mode", {{"mode", "live"}})["op"], "set_mode_ok");
  ASSERT_TRUE(urlab::testing::WaitFor(
      [&] { return manager_.session().engine().step_count() > step + 20; }));
}

TEST_F(StepServerTest, ResetQposMocapOptionsAndKeyframesTakeEffectBeforeTheReply) {
  Play(5000ms, "direct");
  Client c(ctx_, rpc());
  c.Hello({{"observations", "minimal"}});
  const Json keys = c.Op("list_keyframes");
  // Short names beside their articulation (world/names.h); reset takes the short or full name.
  // Each record carries the keyframe's vectors (the whole model's).
  ASSERT_EQ(keys["keyframes"].size(), 1u);
  const Json& bent = keys["keyframes"][0];
  EXPECT_EQ(bent["name"], "bent");
  EXPECT_EQ(bent["articulation"], "arm");
  EXPECT_EQ(bent["full_name"], "arm_bent");
  EXPECT_EQ(bent["qpos"], Json::array({0.7}));
  EXPECT_EQ(bent["time"], 0.0);
  for (const char* f : {"qvel", "ctrl", "mocap_pos", "mocap_quat"}) EXPECT_TRUE(bent.contains(f));
  EXPECT_EQ(c.Op("reset", {{"keyframe_name", "arm_bent"}})["op"], "reset_ok");
  Json r = c.Op("reset", {{"keyframe_name", "bent"}});
  ASSERT_EQ(r["op"], "reset_ok") << r.dump();
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], 0.7);
  EXPECT_EQ(r["time"], 0.0);
  EXPECT_FALSE(r["per_articulation"]["arm"].contains("ctrl"));  // minimal
  r = c.Op("reset", {{"per_articulation_qpos", {{"arm", {{"hinge", -0.25}}}}}});
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], -0.25);
  r = c.Op("set_qpos", {{"articulation", "arm"}, {"qpos", {0.5}}});
  ASSERT_EQ(r["op"], "set_qpos_ok") << r.dump();
  EXPECT_DOUBLE_EQ(r["per_articulation"]["arm"]["qpos"][0], 0.5);
  r = c.Op("set_mocap_pose", {{"body", "arm_target"}, {"pos", {1, 2, 3}}});
  ASSERT_EQ(r["op"], "set_mocap_pose_ok") << r.dump();
  EXPECT_EQ(r["pos"], Json::array({1.0, 2.0, 3.0}));
  EXPECT_EQ(c.Op("read_mocap_pose", {{"body", "arm_target"}})["pos"], r["pos"]);
  r = c.Op("set_sim_options", {{"options", {{"timestep", 0.001}, {"integrator", "RK4"}}}});
  ASSERT_EQ(r["op"], "set_sim_options_ok") << r.dump();
  EXPECT_EQ(r["options"]["timestep"], 0.001);
  EXPECT_EQ(r["options"]["integrator"], mjINT_RK4);
  const double t0 = c.Op("step", {{"n_steps", 4}})["time"];
  EXPECT_NEAR(c.Op("step", {{"n_steps", 4}})["time"].get<double>() - t0, 0.004, 1e-12);
  r = c.Op("forward");
  EXPECT_EQ(r["op"], "forward_ok");
  // A reset refused for its joint values resets nothing.
  const double t_before = r["time"];
  EXPECT_GT(t_before, 0.0);
  EXPECT_EQ(c.Op("reset", {{"per_articulation_qpos", {{"arm", {{"ghost", 1}}}}}})["code"],
            "bad_value");
  EXPECT_EQ(c.Op("reset", {{"per_articulation_qpos", {{"arm", {{"hinge", {1, 2}}}}}}})["code"],
            "dim_mismatch");
  EXPECT_EQ(c.Op("forward")["time"], t_before);
}

// Errors: each bad request gets its code, seq echoed, nothing applied, the server keeps going.
TEST_F(StepServerTest, BadRequestsGetTheirErrorCodes) {
  Play(5000ms, "direct");
  Client c(ctx_, rpc());
  EXPECT_EQ(c.CallRaw("\xc1 not msgpack")["code"], "bad_request");
  EXPECT_EQ(c.Call({{"seq", 1}})["code"], "missing_op");
  const Json unknown = c.Call({{"op", "teleport"}, {"seq", 2}});
  EXPECT_EQ(unknown["code"], "unknown_op");
  EXPECT_EQ(unknown["seq"], 2);
  EXPECT_EQ(c.Call({{"op", "step"}})["code"], "session_expired");
  EXPECT_EQ(c.Call({{"op", "step"}, {"session_id", "stale"}})["code"], "session_expired");
  c.Hello();
  const std::uint64_t before = manager_.session().engine().step_count();
  EXPECT_EQ(c.Op("set_mode")["code"], "missing_field");
  EXPECT_EQ(c.Op("set_mode", {{"mode", "warp"}})["code"], "bad_mode");
  EXPECT_EQ(c.Op("set_paused", {{"paused", "yes"}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"n_steps", 0}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"n_steps", -5}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"n_steps", 1e12}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"leg", {{"ctrl", {1}}}}}}})["code"],
            "unknown_articulation");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl", {1, 2}}}}}}})["code"],
            "dim_mismatch");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl", {"x"}}}}}}})["code"],
            "bad_value");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl_map", {{"nope", 1}}}}}}}})["code"],
            "bad_value");
  EXPECT_EQ(c.Op("reset", {{"keyframe_name", "nope"}})["code"], "unknown_keyframe");
  EXPECT_EQ(c.Op("set_qpos", {{"articulation", "arm"}, {"qpos", {1, 2}}})["code"], "dim_mismatch");
  EXPECT_EQ(c.Op("set_mocap_pose", {{"body", "arm_link"}})["code"], "not_mocap_body");
  EXPECT_EQ(c.Op("set_mocap_pose", {{"body", "ghost"}})["code"], "unknown_body");
  EXPECT_EQ(c.Op("set_sim_options", {{"options", {{"timestep", -1}}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("set_sim_options", {{"options", {{"warp", 9}}}})["code"], "bad_value");
  EXPECT_EQ(manager_.session().engine().step_count(), before);  // nothing stepped
  const Json counters = c.Op("get_counters");
  EXPECT_GE(counters["errors"]["bad_value"].get<int>(), 7);
  EXPECT_EQ(c.Op("step")["op"], "step_ok");  // still serving
}

// Observers read while one driver holds the lease; force takes it over; a silent driver loses
// it after the lease timeout; JSON text clients work beside msgpack ones; DEALER clients too.
TEST_F(StepServerTest, OneDriverManyObserversWithLeases) {
  // A lease of 2 s: the requests between a takeover and the check that the old driver lost the
  // lease must come within it even on a loaded machine (a 300 ms lease could pass during one
  // stall of a busy 2-core CI run and let the old driver step again).
  Play(2000ms, "direct");
  Client a(ctx_, rpc()), b(ctx_, rpc()), observer(ctx_, rpc(), /*json=*/true);
  a.Hello();
  b.Hello();
  const Json hello = observer.Hello();
  EXPECT_FALSE(hello.contains("mjb"));  // bytes travel as base64 text in JSON
  const std::size_t mjb =
      static_cast<std::size_t>(mj_sizeModel(manager_.session().engine().model()));
  EXPECT_EQ(hello["mjb_base64"].get<std::string>().size(), (mjb + 2) / 3 * 4);
  ASSERT_EQ(a.Op("step")["op"], "step_ok");  // a takes the lease
  EXPECT_EQ(b.Op("step")["code"], "not_driver");
  EXPECT_EQ(observer.Op("list_keyframes")["op"], "list_keyframes_ok");  // observers read
  EXPECT_EQ(observer.Op("read_mocap_pose", {{"body", "arm_target"}})["op"], "read_mocap_pose_ok");
  ASSERT_EQ(b.Op("step", {{"force", true}})["op"], "step_ok");  // b takes over
  EXPECT_EQ(a.Op("step")["code"], "not_driver");
  std::this_thread::sleep_for(2200ms);  // b falls silent past the lease timeout
  EXPECT_EQ(a.Op("step")["op"], "step_ok");
  EXPECT_EQ(a.Op("bye")["op"], "bye_ok");  // releases the lease
  EXPECT_EQ(a.Op("step")["code"], "session_expired");
  // A DEALER client (no REQ envelope) is answered too.
  zmq::socket_t dealer(ctx_, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::rcvtimeo, 5000);
  dealer.connect(rpc());
  const std::vector<std::uint8_t> req =
      Json::to_msgpack(Json{{"op", "step"}, {"session_id", b.session()}, {"seq", "d1"}});
  dealer.send(zmq::buffer(req));
  zmq::message_t reply;
  ASSERT_TRUE(dealer.recv(reply));
  const auto* p = static_cast<const std::uint8_t*>(reply.data());
  const Json r = Json::from_msgpack(p, p + reply.size());
  EXPECT_EQ(r["op"], "step_ok");
  EXPECT_EQ(r["seq"], "d1");
}

// xfrc_applied acts for exactly the step window it came with; bad bodies and sizes are refused
// before anything is applied.
TEST_F(StepServerTest, XfrcAppliedActsForItsWindowOnly) {
  Play(5000ms, "direct");
  Client c(ctx_, rpc());
  c.Hello();
  const auto push = [](Json wrench) {
    return Json{{"arm", {{"xfrc_applied", {{"link", std::move(wrench)}}}}}};
  };
  EXPECT_EQ(c.Op("step", {{"per_articulation", push({0, 0, 0, 0, 1})}})["code"], "dim_mismatch");
  EXPECT_EQ(
      c.Op("step", {{"per_articulation",
                     {{"arm", {{"xfrc_applied", {{"ghost", {0, 0, 0, 0, 1, 0}}}}}}}}})["code"],
      "unknown_body");
  EXPECT_EQ(c.Op("step", {{"per_articulation", push({0, 0, 0, 0, "x", 0})}})["code"], "bad_value");
  const Json before = c.Op("step");
  ASSERT_EQ(before["op"], "step_ok");
  EXPECT_EQ(before["per_articulation"]["arm"]["qvel"][0], 0.0);  // nothing was applied
  // A torque about the hinge axis for 10 steps spins the link up ...
  const Json pushed =
      c.Op("step", {{"n_steps", 10}, {"per_articulation", push({0, 0, 0, 0, 1, 0})}});
  ASSERT_EQ(pushed["op"], "step_ok");
  const double spun = pushed["per_articulation"]["arm"]["qvel"][0];
  EXPECT_GT(spun, 0.01);
  // ... and then it is gone: only the joint damping acts (the speed decays, never grows).
  const Json after = c.Op("step", {{"n_steps", 10}});
  const double coasting = after["per_articulation"]["arm"]["qvel"][0];
  EXPECT_LT(coasting, spun);
  EXPECT_GT(coasting, 0.0);
}

TEST_F(StepServerTest, ConfigureControllerPatchesGainsAndEchoesThemAll) {
  Play(5000ms, "live", ", controller: {type: pd, kp: 10, kv: 1}");
  Client c(ctx_, rpc());
  c.Hello();
  const Json r = c.Op(
      "configure_controller",
      {{"articulation", "arm"}, {"params", {{"kv", 3}, {"gains", {{"hinge", {{"kp", 50}}}}}}}});
  ASSERT_EQ(r["op"], "configure_controller_ok") << r.dump();
  EXPECT_EQ(r["kind"], "pd");
  const Json& g = r["params"]["gains"]["motor"];
  EXPECT_EQ(g["kp"], 50.0);
  EXPECT_EQ(g["kv"], 3.0);
  // Refused as a whole: nothing of a bad patch is applied.
  EXPECT_EQ(c.Op("configure_controller",
                 {{"articulation", "arm"}, {"params", {{"kv", 7}, {"kq", 1}}}})["code"],
            "controller_schema_violation");
  EXPECT_EQ(
      c.Op("configure_controller",
           {{"articulation", "arm"}, {"params", {{"gains", {{"ghost", {{"kp", 1}}}}}}}})["code"],
      "controller_schema_violation");
  EXPECT_EQ(
      c.Op("configure_controller", {{"articulation", "arm"}, {"params", {{"kp", -1}}}})["code"],
      "controller_schema_violation");
  const Json same =
      c.Op("configure_controller", {{"articulation", "arm"}, {"params", Json::object()}});
  EXPECT_EQ(same["params"]["gains"]["motor"]["kv"], 3.0);
  EXPECT_EQ(c.Op("set_twist", {{"articulation", "arm"}})["code"], "no_twist_controller")
      << "a fixed base has no twist controller";
  EXPECT_EQ(c.Op("set_twist", {{"articulation", "leg"}})["code"], "unknown_articulation");
}

// Puppet mode: the client owns the state; each step writes it and runs mj_forward, the physics
// thread never steps on its own; wrong lengths are refused whole; the driver leaving returns the
// server to its initial mode.
TEST_F(StepServerTest, PuppetModeWritesTheClientsStateAndNeverSteps) {
  Play();
  Client c(ctx_, rpc());
  c.Hello({{"observations", "full"}});
  const Json mode = c.Op("set_mode", {{"mode", "puppet"}});
  ASSERT_EQ(mode["op"], "set_mode_ok") << mode.dump();
  EXPECT_EQ(mode["current_mode"], "puppet");
  const std::uint64_t steps = manager_.session().engine().step_count();
  Json r = c.Op("step", {{"qpos", {0.3}}, {"qvel", {1.5}}, {"ctrl", {0.7}}, {"time", 4.0}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  EXPECT_EQ(r["time"], 4.0);
  const Json& arm = r["per_articulation"]["arm"];
  EXPECT_EQ(arm["qpos"][0], 0.3);
  EXPECT_EQ(arm["qvel"][0], 1.5);
  EXPECT_EQ(arm["ctrl"][0], 0.7);
  EXPECT_EQ(arm["actuator_force"][0], 0.7);             // mj_forward ran with that control
  EXPECT_NEAR(arm["sensors"]["angle"][0], 0.3, 1e-12);  // and the sensors see that pose
  EXPECT_NEAR(arm["xpos"]["link"][2], 1.0, 1e-12);      // the hinge is at the body origin
  r = c.Op("step", {{"per_articulation", {{"arm", {{"qpos", {-0.4}}, {"qvel", {0}}}}}}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  EXPECT_EQ(r["per_articulation"]["arm"]["qpos"][0], -0.4);
  EXPECT_EQ(r["per_articulation"]["arm"]["qvel"][0], 0.0);
  // Refused whole: nothing of a bad request is written.
  EXPECT_EQ(c.Op("step", {{"qpos", {1.0, 2.0}}})["code"], "dim_mismatch");
  EXPECT_EQ(c.Op("step", {{"qpos", {1.0}}, {"qvel", {1.0, 2.0}}})["code"], "dim_mismatch");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl", {1, 2}}}}}}})["code"],
            "dim_mismatch");
  EXPECT_EQ(c.Op("step", {{"qpos", {std::nan("")}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"qpos", {1.0}}, {"n_steps", 5}})["code"], "bad_value");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"ctrl_map", {{"motor", 1}}}}}}}})["code"],
            "bad_value");  // not a puppet field: refused, not ignored
  EXPECT_EQ(c.Op("step")["code"], "missing_field");
  std::this_thread::sleep_for(30ms);
  r = c.Op("forward");
  EXPECT_EQ(r["per_articulation"]["arm"]["qpos"][0], -0.4);
  EXPECT_EQ(manager_.session().engine().step_count(), steps);  // never stepped
  // Back in live mode, state fields are refused (not silently ignored).
  ASSERT_EQ(c.Op("set_mode", {{"mode", "live"}})["op"], "set_mode_ok");
  EXPECT_EQ(c.Op("step", {{"qpos", {0.1}}})["code"], "bad_mode");
  EXPECT_EQ(c.Op("step", {{"per_articulation", {{"arm", {{"qvel", {0.1}}}}}}})["code"], "bad_mode");
  ASSERT_EQ(c.Op("set_mode", {{"mode", "puppet"}})["op"], "set_mode_ok");
  // The driver says bye: back to live, the loop runs again.
  ASSERT_EQ(c.Op("bye")["op"], "bye_ok");
  Client other(ctx_, rpc());
  EXPECT_EQ(other.Hello()["mode"], "live");
  ASSERT_TRUE(urlab::testing::WaitFor(
      [&] { return manager_.session().engine().step_count() > steps + 10; }));
}

// A driver that disappears in direct mode loses its lease and the simulation runs live again.
TEST_F(StepServerTest, ASilentDriversLockstepEndsWithItsLease) {
  Play(1000ms);  // long enough that the check 50 ms after the step comes within it
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  const std::uint64_t steps = c.Op("step")["step"];
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(manager_.session().engine().step_count(), steps);  // waiting for requests
  ASSERT_TRUE(urlab::testing::WaitFor(
      [&] { return manager_.session().engine().step_count() > steps + 10; }));
  Client other(ctx_, rpc());
  EXPECT_EQ(other.Hello()["mode"], "live");
}

constexpr const char* kBoxXml = R"(<mujoco model="box">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="box" pos="0 0 0.2">
      <freejoint name="root"/>
      <geom name="shell" type="box" size="0.1 0.1 0.1" mass="2"/>
    </body>
    <body name="ball" pos="1 0 0.2">
      <freejoint name="ball_root"/>
      <geom name="ball_geom" type="sphere" size="0.05" mass="0.5"/>
    </body>
  </worldbody>
</mujoco>
)";

TEST_F(StepServerTest, SetTwistDrivesTheFreeBase) {
  urlab::testing::WriteTextFile(dir_, "box.xml", kBoxXml);
  Play(5000ms, "direct", ", twist: {mode: hover}", "box.xml");  // a body without legs
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(c.Op("set_twist", {{"articulation", "arm"}, {"linear", {0.5, 0, 0}}})["code"],
            "missing_field");
  EXPECT_EQ(c.Op("set_twist",
                 {{"articulation", "arm"}, {"linear", {0.5, 0}}, {"angular", {0, 0, 0}}})["code"],
            "dim_mismatch");
  // Clamped to the default maxima (1 m/s forward, 1.5 rad/s) and echoed.
  const Json r =
      c.Op("set_twist", {{"articulation", "arm"}, {"linear", {5.0, 0, 0}}, {"angular", {0, 0, 0}}});
  ASSERT_EQ(r["op"], "set_twist_ok") << r.dump();
  EXPECT_EQ(r["linear"], Json::array({1.0, 0.0, 0.0}));
  const Json s = c.Op("step", {{"n_steps", 1000}});
  ASSERT_EQ(s["op"], "step_ok");
  // Observations carry the twist while the controller is attached (the box, 2 kg on the floor,
  // does not slide: the controller's force, 2 kg * 4/s * 1 m/s, is below its friction).
  EXPECT_EQ(s["per_articulation"]["arm"]["twist"], Json::array({1.0, 0.0, 0.0})) << s.dump();
  EXPECT_EQ(s["per_articulation"]["arm"]["actions"], 0);
}

TEST_F(StepServerTest, FireLauncherLaunchesBeforeTheReply) {
  // The last argument closes the articulation's entry and opens a launcher's.
  Play(5000ms, "direct", "}\nlaunchers:\n  - {name: gun, pos: [0.5, 0, 1], speed: 2");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(c.Op("fire_launcher", {{"launcher", "cannon"}})["code"], "unknown_launcher");
  const Json r = c.Op("fire_launcher", {{"launcher", "gun"}});
  ASSERT_EQ(r["op"], "fire_launcher_ok") << r.dump();
  EXPECT_EQ(r["projectile"], 0);
  EXPECT_EQ(c.Op("fire_launcher", {{"launcher", "gun"}})["projectile"], 1);
  // Direct mode: nothing stepped, so the state shows the launch exactly.
  const world::LauncherLayout& l = manager_.session().launchers()[0];
  manager_.session().engine().WithLockedData([&](const mjModel*, mjData* d) {
    EXPECT_EQ(d->qvel[l.qvel_adr[0]], 2);
    EXPECT_EQ(d->qpos[l.qpos_adr[0]], l.muzzle[0]);
  });
}

TEST_F(StepServerTest, GetContactsListsForcesWithFilterAndLimit) {
  urlab::testing::WriteTextFile(dir_, "box.xml", kBoxXml);
  Play(5000ms, "direct", "", "box.xml");
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("step", {{"n_steps", 500}})["op"], "step_ok");  // 1 s: both at rest
  Json r = c.Op("get_contacts");
  ASSERT_EQ(r["op"], "get_contacts_ok") << r.dump();
  EXPECT_EQ(r["truncated"], false);
  EXPECT_EQ(r["count"], r["matched"]);
  ASSERT_EQ(r["contacts"].size(), r["count"].get<std::size_t>());
  double box_normal = 0, ball_normal = 0;
  for (const Json& k : r["contacts"]) {
    EXPECT_EQ(k["geom1"], "arm_floor");  // the plane comes first in MuJoCo's pairs
    EXPECT_EQ(k["body1"], "world");
    EXPECT_EQ(k["normal"], Json::array({k["frame"][0], k["frame"][1], k["frame"][2]}));
    EXPECT_NEAR(k["normal"][2].get<double>(), 1.0, 1e-9);
    EXPECT_LT(std::abs(k["dist"].get<double>()), 1e-2);
    ASSERT_EQ(k["force"].size(), 6u);
    (k["body2"] == "arm_box" ? box_normal : ball_normal) += k["force"][0].get<double>();
  }
  // At rest the normal forces carry the weights (2 kg and 0.5 kg).
  EXPECT_NEAR(box_normal, 2 * 9.81, 0.2);
  EXPECT_NEAR(ball_normal, 0.5 * 9.81, 0.05);
  // Filter: only the ball's contact, whichever side is named.
  r = c.Op("get_contacts", {{"filter", {{"body1", "arm_ball"}}}});
  ASSERT_EQ(r["count"], 1) << r.dump();
  EXPECT_EQ(r["contacts"][0]["geom2"], "arm_ball_geom");
  r = c.Op("get_contacts", {{"filter", {{"geom1", "arm_shell"}, {"geom2", "arm_floor"}}}});
  EXPECT_GE(r["count"].get<int>(), 1);
  for (const Json& k : r["contacts"]) EXPECT_EQ(k["geom2"], "arm_shell");
  // Limit: the rest are counted and flagged.
  r = c.Op("get_contacts", {{"max_contacts", 1}});
  EXPECT_EQ(r["count"], 1);
  EXPECT_GT(r["matched"].get<int>(), 1);
  EXPECT_EQ(r["truncated"], true);
  EXPECT_EQ(c.Op("get_contacts", {{"filter", {{"body1", "ghost"}}}})["code"], "unknown_body");
  EXPECT_EQ(c.Op("get_contacts", {{"filter", {{"geom1", "ghost"}}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("get_contacts", {{"filter", {{"site", "x"}}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("get_contacts", {{"max_contacts", -1}})["code"], "bad_value");
  // An observer may ask too.
  Client observer(ctx_, rpc());
  observer.Hello();
  EXPECT_EQ(observer.Op("get_contacts")["op"], "get_contacts_ok");
}

// Binary STL of a tetrahedron (4 triangles).
std::string TetrahedronStl() {
  const float v[4][3] = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::string out(80, ' ');
  const std::uint32_t n = 4;
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& f : faces) {
    const float normal[3] = {0, 0, 0};
    out.append(reinterpret_cast<const char*>(normal), 12);
    for (int k : f) out.append(reinterpret_cast<const char*>(v[k]), 12);
    out.append(2, '\0');
  }
  return out;
}

// hello with include_assets: the composed model with bare asset names and the files' bytes,
// enough to compile the same model in an empty folder elsewhere.
TEST_F(StepServerTest, HelloIncludeAssetsShipsAModelThatCompilesElsewhere) {
  urlab::testing::WriteTextFile(dir_, "meshes/tet.stl", TetrahedronStl());
  urlab::testing::WriteTextFile(dir_, "tet.xml", R"(<mujoco model="tet">
  <compiler meshdir="meshes"/>
  <asset><mesh name="tet" file="tet.stl"/></asset>
  <worldbody>
    <body name="piece" pos="0 0 1">
      <joint name="slide" type="slide" axis="0 0 1"/>
      <geom type="mesh" mesh="tet" density="1000"/>
    </body>
  </worldbody>
</mujoco>
)");
  Play(5000ms, "live", "", "tet.xml");
  Client c(ctx_, rpc());
  const Json h = c.Hello({{"include_assets", true}});
  ASSERT_EQ(h["op"], "hello_ok") << h.dump().substr(0, 300);
  const std::string xml = h["mjcf_compiled"];
  EXPECT_NE(xml.find("file=\"tet.stl\""), std::string::npos) << xml;
  EXPECT_EQ(xml.find(dir_), std::string::npos);  // no path of this machine
  ASSERT_TRUE(h["vfs_assets"]["tet.stl"].is_binary());
  const auto& bytes = h["vfs_assets"]["tet.stl"].get_binary();
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), TetrahedronStl());
  // Elsewhere: an empty folder with the XML and the files under their bare names.
  const std::string there = urlab::testing::MakeTempDir("include_assets");
  urlab::testing::WriteTextFile(there, "model.xml", xml);
  urlab::testing::WriteTextFile(there, "tet.stl", std::string(bytes.begin(), bytes.end()));
  char error[1000] = "";
  mjModel* m = mj_loadXML((there + "/model.xml").c_str(), nullptr, error, sizeof error);
  ASSERT_NE(m, nullptr) << error;
  const mjModel* here = manager_.session().engine().model();
  EXPECT_EQ(m->nmesh, here->nmesh);
  EXPECT_EQ(m->nmeshvert, here->nmeshvert);
  EXPECT_EQ(m->nq, here->nq);
  EXPECT_DOUBLE_EQ(m->body_mass[1], here->body_mass[1]);
  mj_deleteModel(m);
  // JSON sessions get the same files as base64 text.
  Client text(ctx_, rpc(), /*json=*/true);
  const Json t = text.Hello({{"include_assets", true}});
  EXPECT_EQ(t["vfs_assets_base64"]["tet.stl"].get<std::string>().size(),
            (bytes.size() + 2) / 3 * 4);
  EXPECT_EQ(t["mjcf_compiled"], xml);
}

// A driver waiting for a step longer than the lease timeout keeps its lease (and its mode).
TEST_F(StepServerTest, ALongStepDoesNotCostTheDriverItsLease) {
  Play(200ms, "live", "", URLAB_SOURCE_DIR "/examples/models/humanoid.xml");
  Client c(ctx_, rpc());
  c.Hello({{"observations", "minimal"}});
  ASSERT_EQ(c.Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  const auto t0 = std::chrono::steady_clock::now();
  const Json r = c.Op("step", {{"n_steps", 20000}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  const auto took = std::chrono::steady_clock::now() - t0;
  const Json counters = c.Op("get_counters");
  if (took > 300ms) {  // (on a very fast machine the step may be shorter than the lease)
    EXPECT_EQ(counters["mode"], "direct");
    EXPECT_EQ(counters["driver"], c.session());
  }
  EXPECT_EQ(c.Op("step")["op"], "step_ok");
}

// JSON with binary arrays: vectors become <field>_base64; the structure's keys stay as they are.
TEST_F(StepServerTest, JsonBinaryArraysTravelAsBase64Fields) {
  Play(5000ms, "direct");
  Client c(ctx_, rpc(), /*json=*/true);
  c.Hello({{"arrays", "binary"}});
  for (const char* level : {"minimal", "standard", "full"}) {
    const Json r = c.Op("step", {{"observations", level}});
    ASSERT_EQ(r["op"], "step_ok") << r.dump();
    ASSERT_TRUE(r["per_articulation"].contains("arm")) << level << ": " << r.dump();
    const Json& arm = r["per_articulation"]["arm"];
    EXPECT_EQ(arm["qpos_base64"].get<std::string>().size(), 12u) << level;  // 8 bytes
    EXPECT_FALSE(arm.contains("qpos")) << level;
    if (std::string(level) != "minimal") {
      EXPECT_TRUE(arm["sensors_base64"].contains("angle")) << level << ": " << arm.dump();
    }
  }
}

}  // namespace
}  // namespace urlab::net::tests
