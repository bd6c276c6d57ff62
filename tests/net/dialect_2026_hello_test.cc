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

}  // namespace
}  // namespace urlab::net::tests
