// The 2026 dialect's handshake and observations with free bodies of no articulation (a
// launcher's projectiles) beside an articulation that has a free body of its own: the entities
// array lists the free bodies after the articulations, and every observation carries their state
// under `scene` (2026) and `entities` (ours). Real step server, real sockets on loopback with
// ephemeral ports; requests written from docs/protocol.md.
#include <gtest/gtest.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>
#include <zmq.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"

// A namespace of their own: their plain nlohmann::json alias must not meet net::Json (the
// ordered one) where a unity build puts several test files in one translation unit.
namespace urlab::net::tests {
namespace {

using namespace std::chrono_literals;
using Json = nlohmann::json;
using test_client::Client;

// An arm with a free-floating ball of its own (the articulation's: not a free body of the scene).
constexpr const char* kArmWithBallXml = R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
    <body name="ball" pos="1 0 0.5">
      <freejoint name="ball_free"/>
      <geom type="sphere" size="0.05" mass="0.1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
</mujoco>
)";

constexpr int kPool = 3;

class Dialect2026HelloTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override {
    urlab::testing::WriteTextFile(dir_, "arm.xml", kArmWithBallXml);
    Serve(
        "control_source: network\narticulations:\n  - {name: arm, mjcf: arm.xml}\n"
        "launchers:\n  - {name: gun, pos: [0.5, 0, 1], speed: 2, pool: " +
            std::to_string(kPool) + "}\n",
        urlab::testing::AutoPorts("direct"));
  }
};

TEST_F(Dialect2026HelloTest, FreeBodiesOfNoArticulationAreEntitiesWithTheirStateInScene) {
  Client c(ctx_, net_->endpoints().rpc);
  const Json h = c.Hello({{"client_version", "urlab_bridge/2026.1.0"}, {"raw_model", true}});
  ASSERT_EQ(h["op"], "hello_ok") << h.dump();
  const Json& entities = h["entities"];
  ASSERT_TRUE(entities.is_array());
  ASSERT_EQ(entities.size(), 1u + kPool) << entities.dump();
  EXPECT_EQ(entities[0]["prefix"], "arm");
  EXPECT_EQ(entities[0]["kind"], "articulation");

  const world::LauncherLayout& gun = manager_.session().launchers()[0];
  const mjModel* m = manager_.session().engine().model();
  std::set<std::string> names;
  for (int i = 0; i < kPool; ++i) {
    const Json& e = entities[static_cast<std::size_t>(1 + i)];
    SCOPED_TRACE(e.dump());
    const int body = gun.bodies[static_cast<std::size_t>(i)];
    const std::string name = mj_id2name(m, mjOBJ_BODY, body);
    EXPECT_EQ(e["prefix"], name);
    EXPECT_EQ(e["actor_name"], name);
    EXPECT_EQ(e["actor_id"], 1 + i);
    EXPECT_EQ(e["kind"], "projectile");
    EXPECT_EQ(e["id"], body);
    EXPECT_EQ(e["has_free_base"], true);
    EXPECT_EQ(e["qpos_offset"], 0);
    EXPECT_EQ(e["qvel_offset"], 0);
    EXPECT_EQ(e["qpos_adr"], gun.qpos_adr[static_cast<std::size_t>(i)]);
    EXPECT_EQ(e["qvel_adr"], gun.qvel_adr[static_cast<std::size_t>(i)]);
    // The free joint by the name the raw tables give it.
    bool in_raw = false;
    for (const Json& j : h["raw_joints"]) {
      in_raw = in_raw || (j["name"] == e["free_joint"] && j["type"] == mjJNT_FREE &&
                          j["body_id"] == body && j["qpos_adr"] == e["qpos_adr"]);
    }
    EXPECT_TRUE(in_raw) << "free_joint " << e["free_joint"];
    // Its own raw tables (the client's name maps): the free joint alone.
    EXPECT_EQ(e["raw_model"], true);
    ASSERT_EQ(e["raw_joints"].size(), 1u);
    EXPECT_EQ(e["raw_joints"][0]["name"], e["free_joint"]);
    EXPECT_EQ(e["raw_joints"][0]["type"], mjJNT_FREE);
    EXPECT_EQ(e["raw_joints"][0]["qpos_adr"], e["qpos_adr"]);
    EXPECT_EQ(e["raw_joints"][0]["qpos_index"], 0);
    EXPECT_EQ(e["raw_actuators"], Json::array());
    EXPECT_EQ(e["raw_sensors"], Json::array());
    // original_names by category, live -> original.
    EXPECT_TRUE(e["original_names"]["bodies"].contains(name)) << e["original_names"].dump();
    EXPECT_EQ(e["original_names"]["actuators"], Json::object());
    // What an articulation's element carries, empty: the client reads every element alike.
    EXPECT_EQ(e["default_control_mode"], "raw");
    EXPECT_EQ(e["controller"]["schema"], Json::object());
    EXPECT_EQ(e["actuator_types"], Json::object());
    EXPECT_TRUE(e["camera_topics"].is_object());
    names.insert(name);
  }
  EXPECT_EQ(names.size(), static_cast<std::size_t>(kPool));
  for (const Json& e : entities) EXPECT_NE(e["prefix"], "arm_ball") << "the arm's own ball";

  // Observations: each free body's qpos (7) and qvel (6) under scene, at offset 0; a launch
  // shows at once (direct mode).
  ASSERT_EQ(c.Op("fire_launcher", {{"launcher", "gun"}})["op"], "fire_launcher_ok");
  const Json r = c.Op("step", {{"n_steps", 1}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  ASSERT_TRUE(r["scene"].is_object());
  ASSERT_EQ(r["scene"].size(), static_cast<std::size_t>(kPool));
  const std::string first = entities[1]["prefix"];
  const Json& shot = r["scene"][first];
  ASSERT_EQ(shot["qpos"].size(), 7u);
  ASSERT_EQ(shot["qvel"].size(), 6u);
  manager_.session().engine().WithLockedData([&](const mjModel*, mjData* d) {
    for (int k = 0; k < 7; ++k) EXPECT_EQ(shot["qpos"][k], d->qpos[gun.qpos_adr[0] + k]);
    for (int k = 0; k < 6; ++k) EXPECT_EQ(shot["qvel"][k], d->qvel[gun.qvel_adr[0] + k]);
  });
  EXPECT_GT(shot["qvel"][0].get<double>(), 1.0) << "the launched projectile moves";

  // Our vocabulary: the same map under `entities`.
  Client ours(ctx_, net_->endpoints().rpc);
  const Json oh = ours.Hello();
  ASSERT_TRUE(oh["entities"].is_object());
  ASSERT_EQ(oh["entities"].size(), static_cast<std::size_t>(kPool));
  EXPECT_EQ(oh["entities"][first]["qpos_adr"], gun.qpos_adr[0]);
  EXPECT_EQ(oh["entities"][first]["kind"], "projectile");
  const Json fwd = ours.Op("forward");
  ASSERT_EQ(fwd["op"], "forward_ok") << fwd.dump();
  ASSERT_EQ(fwd["entities"].size(), static_cast<std::size_t>(kPool));
  EXPECT_EQ(fwd["entities"][first]["qpos"], shot["qpos"]);
  EXPECT_FALSE(fwd.contains("scene"));
}

// Two articulations of one file (the second's ids and addresses after the first's), one under a
// PD controller, with a hinge and a slide, a motor and a position servo, and a sensor.
constexpr const char* kTwoJointXml = R"(<mujoco model="two">
  <option timestep="0.002"/>
  <worldbody>
    <body name="base" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" range="-1 1" damping="0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      <body name="tip" pos="0.3 0 0">
        <joint name="slide" type="slide" axis="1 0 0" range="0 0.2" damping="1"/>
        <geom type="sphere" size="0.04" mass="0.2"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" ctrlrange="-2 2"/>
    <position name="servo" joint="slide" kp="50" ctrlrange="0 0.2"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
  </sensor>
</mujoco>
)";

class Dialect2026RawTablesTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override {
    urlab::testing::WriteTextFile(dir_, "two.xml", kTwoJointXml);
    Serve(
        "control_source: network\narticulations:\n"
        "  - {name: first, mjcf: two.xml, controller: {type: pd, kp: 40, kv: 2}}\n"
        "  - {name: second, mjcf: two.xml, pos: [1, 0, 0]}\n",
        urlab::testing::AutoPorts("direct"));
  }
};

// The 2026 client builds its name maps from the raw tables inside each element of `entities`
// (it never asks for them, and reads no top-level raw_model): every hello_ok carries them, names
// short, ids and addresses the compiled model's, in the order of the articulation's vectors.
TEST_F(Dialect2026RawTablesTest, EveryEntityCarriesItsOwnRawTablesInEveryHello) {
  Client c(ctx_, net_->endpoints().rpc);
  const mjModel* m = manager_.session().engine().model();
  for (int round = 0; round < 2; ++round) {  // a refreshed session's hello too
    SCOPED_TRACE("hello " + std::to_string(round));
    const Json h = c.Hello({{"client_version", "urlab_bridge/2026.1.0"}});
    ASSERT_EQ(h["op"], "hello_ok") << h.dump();
    EXPECT_FALSE(h.contains("raw_joints")) << "the whole model's tables only when asked";
    ASSERT_EQ(h["entities"].size(), 2u);
    for (const Json& e : h["entities"]) {
      const std::string art = e["prefix"];
      SCOPED_TRACE(art);
      EXPECT_EQ(e["raw_model"], true);
      const auto id = [&](mjtObj type, const std::string& name) {
        return mj_name2id(m, type, (art + "_" + name).c_str());
      };
      const Json& joints = e["raw_joints"];
      ASSERT_EQ(joints.size(), 2u) << joints.dump();
      const char* joint_names[] = {"hinge", "slide"};
      for (std::size_t k = 0; k < 2; ++k) {
        const Json& j = joints[k];
        const int jid = id(mjOBJ_JOINT, joint_names[k]);
        ASSERT_GE(jid, 0);
        EXPECT_EQ(j["name"], joint_names[k]);
        EXPECT_EQ(j["id"], jid);
        EXPECT_EQ(j["type"], m->jnt_type[jid]);
        EXPECT_EQ(j["qpos_adr"], m->jnt_qposadr[jid]);
        EXPECT_EQ(j["qvel_adr"], m->jnt_dofadr[jid]);
        EXPECT_EQ(j["body_id"], m->jnt_bodyid[jid]);
        EXPECT_EQ(j["range"], Json({m->jnt_range[2 * jid], m->jnt_range[2 * jid + 1]}));
        EXPECT_EQ(j["qpos_index"], k);  // into arts[prefix].qpos
        EXPECT_EQ(j["qvel_index"], k);
      }
      const Json& actuators = e["raw_actuators"];
      ASSERT_EQ(actuators.size(), 2u) << actuators.dump();
      const char* actuator_names[] = {"motor", "servo"};
      for (std::size_t k = 0; k < 2; ++k) {
        const Json& u = actuators[k];
        const int uid = id(mjOBJ_ACTUATOR, actuator_names[k]);
        ASSERT_GE(uid, 0);
        EXPECT_EQ(u["name"], actuator_names[k]);
        EXPECT_EQ(u["id"], uid);
        EXPECT_EQ(u["index"], k);  // into arts[prefix].ctrl
        EXPECT_EQ(u["joint"], joint_names[k]);
        EXPECT_EQ(u["ctrlrange"],
                  Json({m->actuator_ctrlrange[2 * uid], m->actuator_ctrlrange[2 * uid + 1]}));
        ASSERT_EQ(u["gear"].size(), 6u);
        EXPECT_EQ(u["gear"][0], m->actuator_gear[6 * uid]);
      }
      const Json& sensors = e["raw_sensors"];
      ASSERT_EQ(sensors.size(), 1u) << sensors.dump();
      const int sid = id(mjOBJ_SENSOR, "angle");
      EXPECT_EQ(sensors[0]["name"], "angle");
      EXPECT_EQ(sensors[0]["id"], sid);
      EXPECT_EQ(sensors[0]["type"], mjSENS_JOINTPOS);
      EXPECT_EQ(sensors[0]["adr"], m->sensor_adr[sid]);
      EXPECT_EQ(sensors[0]["dim"], 1);
    }
    // The second's ids come after the first's: its indices are not its ids.
    EXPECT_EQ(h["entities"][1]["raw_actuators"][0]["id"], 2);
    EXPECT_EQ(h["entities"][1]["raw_actuators"][0]["index"], 0);
  }

  // A step with a ctrl vector built from the maps: name -> index, len(raw_actuators) values.
  const Json h = c.Hello({{"client_version", "urlab_bridge/2026.1.0"}});
  const Json& second = h["entities"][1];
  std::vector<double> ctrl(second["raw_actuators"].size(), 0.0);
  for (const Json& u : second["raw_actuators"]) {
    if (u["name"] == "servo") ctrl[u["index"].get<std::size_t>()] = 0.125;
    if (u["name"] == "motor") ctrl[u["index"].get<std::size_t>()] = -0.5;
  }
  const Json r = c.Op("step", {{"arts", {{"second", {{"ctrl", ctrl}, {"control_mode", "raw"}}}}}});
  ASSERT_EQ(r["op"], "step_ok") << r.dump();
  EXPECT_EQ(r["arts"]["second"]["ctrl"], Json({-0.5, 0.125}));
}

// original_names by category, live name (the compiled model's) -> original (the MJCF's): the
// client inverts each map to find the name a user wrote. A flat map is ignored by it.
TEST_F(Dialect2026RawTablesTest, OriginalNamesAreNestedByCategoryLiveToOriginal) {
  Client c(ctx_, net_->endpoints().rpc);
  const Json h = c.Hello({{"client_version", "urlab_bridge/2026.1.0"}});
  ASSERT_EQ(h["op"], "hello_ok") << h.dump();
  const Json& o = h["entities"][1]["original_names"];
  EXPECT_EQ(o["actuators"], Json({{"second_motor", "motor"}, {"second_servo", "servo"}}));
  EXPECT_EQ(o["joints"], Json({{"second_hinge", "hinge"}, {"second_slide", "slide"}}));
  EXPECT_EQ(o["sensors"], Json({{"second_angle", "angle"}}));
  EXPECT_EQ(o["bodies"]["second_base"], "base");
  EXPECT_EQ(o["bodies"]["second_tip"], "tip");
  EXPECT_EQ(o.size(), 4u) << o.dump();
}

// controller.schema: {param: {type: per_joint | scalar, min?, max?}}, a map per entry (the
// client calls .get on each; a bare type string fails inside it); the values it checks against
// min before sending are the ones configure_controller accepts.
TEST_F(Dialect2026RawTablesTest, ControllerSchemaEntriesAreMapsWithTypeAndBounds) {
  Client c(ctx_, net_->endpoints().rpc);
  const Json h = c.Hello({{"client_version", "urlab_bridge/2026.1.0"}});
  ASSERT_EQ(h["op"], "hello_ok") << h.dump();
  const Json& schema = h["entities"][0]["controller"]["schema"];
  for (const char* key : {"kp", "kv", "torque_limit"}) {
    ASSERT_TRUE(schema[key].is_object()) << key << ": " << schema.dump();
    EXPECT_EQ(schema[key]["type"], "per_joint") << key;
    EXPECT_EQ(schema[key]["min"], 0.0) << key;
  }
  for (const char* key : {"default_kp", "default_kv", "default_torque_limit"}) {
    ASSERT_TRUE(schema[key].is_object()) << key << ": " << schema.dump();
    EXPECT_EQ(schema[key]["type"], "scalar") << key;
    EXPECT_EQ(schema[key]["min"], 0.0) << key;
  }
  EXPECT_EQ(schema.size(), 6u) << schema.dump();
  // At the bound: taken; below it: refused by the server as by the client.
  const Json ok = c.Op("configure_controller",
                       {{"articulation", "first"}, {"params", {{"kp", {{"motor", 0.0}}}}}});
  EXPECT_EQ(ok["op"], "configure_controller_ok") << ok.dump();
  const Json below =
      c.Op("configure_controller", {{"articulation", "first"}, {"params", {{"default_kv", -1.0}}}});
  EXPECT_EQ(below["code"], "controller_schema_violation") << below.dump();
  // An articulation without gains: an empty schema, as before.
  EXPECT_EQ(h["entities"][1]["controller"]["schema"], Json::object());
}

}  // namespace
}  // namespace urlab::net::tests
