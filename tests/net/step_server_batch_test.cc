// The step server's batch operations (batch_info, batch_step, batch_reset) over a run of N
// environments (world::BatchSubsystem: environment 0 is the engine's own simulation, 1..N-1 a
// physics::Batch stepped with it). Real sockets on loopback with ephemeral ports, real MuJoCo; the
// client encodes msgpack itself from the protocol's description.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <zmq.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"
#include "support/wait.h"
#include "urlab/world/batch_subsystem.h"

// A namespace of their own: their plain nlohmann::json alias must not meet net::Json (the
// ordered one) where a unity build puts several test files in one translation unit.
namespace urlab::net::tests {
namespace {

using namespace std::chrono_literals;
using Json = nlohmann::json;
using test_client::Client;

// A pendulum under gravity (its path depends on the reset noise) with a motor and a sensor.
constexpr const char* kPendulumXml = R"(<mujoco model="pendulum">
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge" ctrlrange="-5 5" ctrllimited="true"/>
  </actuator>
  <sensor>
    <jointvel name="speed" joint="hinge"/>
  </sensor>
</mujoco>
)";

Json Packed(const std::vector<double>& v) {
  const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
  return Json::binary(std::vector<std::uint8_t>(p, p + v.size() * sizeof(double)));
}

template <typename T>
std::vector<T> Unpack(const Json& v) {
  const auto& bytes = v.get_binary();
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

class StepServerBatchTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override { urlab::testing::WriteTextFile(dir_, "pendulum.xml", kPendulumXml); }
  void Play(world::BatchSubsystemOptions b, const std::string& mode = "direct",
            const std::string& scene = "articulations:\n  - {name: pend, mjcf: pendulum.xml}\n") {
    batch_ = &static_cast<world::BatchSubsystem&>(
        manager_.AddSubsystem(std::make_unique<world::BatchSubsystem>(b)));
    Serve(scene, urlab::testing::AutoPorts(mode),
          [&](NetworkSubsystem& net) { net.SetBatch(batch_); });
  }
  // Steps with `actions` (one per environment: one actuator).
  Json Step(Client& c, const std::vector<double>& actions, Json extra = Json::object()) {
    extra["actions"] = Packed(actions);
    return c.Op("batch_step", extra);
  }

  world::BatchSubsystem* batch_ = nullptr;
};

TEST_F(StepServerBatchTest, InfoDescribesTheBatchAndAStepStepsEveryEnvironment) {
  Play({.envs = 4, .threads = 2});
  Client c(ctx_, rpc());
  const Json hello = c.Hello();
  EXPECT_EQ(hello["batch"]["envs"], 4);
  const Json info = c.Op("batch_info");
  ASSERT_EQ(info["op"], "batch_info_ok") << info.dump();
  EXPECT_EQ(info["envs"], 4);
  EXPECT_EQ(info["threads"], 2);
  EXPECT_EQ(info["nu"], 1);
  EXPECT_EQ(info["obs_size"], 3);  // qpos, qvel, the sensor
  EXPECT_EQ(info["obs_layout"][2]["name"], "sensordata");
  EXPECT_EQ(Unpack<double>(info["action_low"]), std::vector<double>{-5});
  EXPECT_EQ(Unpack<double>(info["action_high"]), std::vector<double>{5});
  const std::uint64_t engine_steps = manager_.session().engine().step_count();
  // Two environments with one action, two with another: equal actions, equal states.
  Json r;
  for (int i = 0; i < 10; ++i) {
    r = Step(c, {1.0, -1.0, 1.0, -1.0}, {{"n_steps", 2}});
    ASSERT_EQ(r["op"], "batch_step_ok") << r.dump();
  }
  const auto obs = Unpack<double>(r["obs"]);
  ASSERT_EQ(obs.size(), 12u);
  EXPECT_EQ(Unpack<std::uint8_t>(r["done"]), std::vector<std::uint8_t>(4, 0));
  for (double t : Unpack<double>(r["time"])) EXPECT_NEAR(t, 20 * 0.002, 1e-12);
  EXPECT_EQ(Unpack<std::uint32_t>(r["episode_steps"]), std::vector<std::uint32_t>(4, 20));
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(obs[k], obs[6 + k]);      // environment 0 (the engine's) and 2 (the batch's)
    EXPECT_EQ(obs[3 + k], obs[9 + k]);  // 1 and 3
  }
  EXPECT_GT(obs[1], obs[4]);  // the positive torque turned its pendulum faster
  EXPECT_NE(obs[2], 0.0);     // the sensor reads the joint speed
  // Environment 0 is the engine's simulation: its steps are the engine's.
  EXPECT_EQ(manager_.session().engine().step_count(), engine_steps + 20);
}

TEST_F(StepServerBatchTest, BadRequestsAreRefusedBeforeAnythingSteps) {
  Play({.envs = 3, .threads = 2});
  Client c(ctx_, rpc()), other(ctx_, rpc());
  c.Hello();
  other.Hello();
  const std::uint64_t before = manager_.session().engine().step_count();
  EXPECT_EQ(Step(c, {1, 2})["code"], "dim_mismatch");
  EXPECT_EQ(Step(c, {1, 2, 3, 4})["code"], "dim_mismatch");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Json bad = Step(c, {0, nan, 0});
  EXPECT_EQ(bad["code"], "bad_value");
  EXPECT_NE(bad["message"].get<std::string>().find("environment 1"), std::string::npos);
  EXPECT_EQ(Step(c, {0, std::numeric_limits<double>::infinity(), 0})["code"], "bad_value");
  EXPECT_EQ(Step(c, {0, 1e12, 0})["code"], "bad_value");  // outside the range of actions
  EXPECT_EQ(c.Op("batch_step", {{"actions", "many"}})["code"], "bad_value");
  EXPECT_EQ(c.Op("batch_step")["code"], "missing_field");
  EXPECT_EQ(Step(c, {0, 0, 0}, {{"reset", {true}}})["code"], "dim_mismatch");
  EXPECT_EQ(Step(c, {0, 0, 0}, {{"n_steps", 0}})["code"], "bad_value");
  EXPECT_EQ(c.Op("batch_reset", {{"envs", {3}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("batch_reset", {{"seeds", {1, 2}}})["code"], "dim_mismatch");
  EXPECT_EQ(c.Op("batch_reset", {{"seed", -1}})["code"], "bad_value");
  EXPECT_EQ(c.Op("batch_reset", {{"seed", 1}, {"seeds", {1, 2, 3}}})["code"], "bad_value");
  EXPECT_EQ(manager_.session().engine().step_count(), before);  // nothing stepped
  // The lease: the first driver's steps take it; another client is refused.
  ASSERT_EQ(Step(c, {0, 0, 0})["op"], "batch_step_ok");
  EXPECT_EQ(Step(other, {0, 0, 0})["code"], "not_driver");
  EXPECT_EQ(other.Op("batch_reset")["code"], "not_driver");
  EXPECT_EQ(other.Op("batch_info")["op"], "batch_info_ok");  // observers read
  // Live mode does not step in lockstep.
  ASSERT_EQ(c.Op("set_mode", {{"mode", "live"}})["op"], "set_mode_ok");
  EXPECT_EQ(Step(c, {0, 0, 0})["code"], "bad_mode");
}

TEST_F(StepServerBatchTest, TheSameSeedGivesTheSameEpisodeInEveryEnvironment) {
  Play({.envs = 4, .threads = 2, .reset_noise = 0.3});
  Client c(ctx_, rpc());
  c.Hello();
  const auto run = [&](const Json& seeds) {
    const Json reset = c.Op("batch_reset", {{"seeds", seeds}});
    EXPECT_EQ(reset["op"], "batch_reset_ok") << reset.dump();
    std::vector<std::vector<double>> path{Unpack<double>(reset["obs"])};
    EXPECT_EQ(Unpack<double>(reset["time"]), std::vector<double>(4, 0.0));
    for (int i = 0; i < 25; ++i) {
      const double a = std::sin(0.3 * i);
      const Json r = Step(c, {a, a, a, a}, {{"n_steps", 2}});
      EXPECT_EQ(r["op"], "batch_step_ok") << r.dump();
      path.push_back(Unpack<double>(r["obs"]));
    }
    return path;
  };
  const auto first = run(Json{7, 8, 7, 9});
  for (const auto& obs : first) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(obs[k], obs[6 + k]);  // 0 and 2: seed 7
  }
  EXPECT_NE(first[0][0], first[0][3]);  // seeds 7 and 8 start apart
  EXPECT_NE(first[0][3], first[0][9]);  // 8 and 9 too
  EXPECT_NE(first[0][0], first[0][9]);
  // Again with the seeds moved: the episode follows its seed, whichever environment runs it.
  const auto second = run(Json{9, 7, 8, 7});
  for (std::size_t s = 0; s < first.size(); ++s) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(second[s][3 + k], first[s][k]);      // seed 7: env 1 now, env 0 before
      EXPECT_EQ(second[s][9 + k], first[s][k]);      // seed 7: env 3
      EXPECT_EQ(second[s][6 + k], first[s][3 + k]);  // seed 8
      EXPECT_EQ(second[s][k], first[s][9 + k]);      // seed 9: env 0 (the engine's) now
    }
  }
  // `seed`: environment i gets seed + i.
  const Json reset = c.Op("batch_reset", {{"seed", 7}, {"envs", {0}}});
  EXPECT_EQ(Unpack<double>(reset["obs"])[0], first[0][0]);
}

TEST_F(StepServerBatchTest, EveryRowIsItsEnvironmentWhicheverTheEngineSteps) {
  // The engine's simulation is environment 2: the batch's rows go around it (the stepping
  // threads write them in a window's last iteration; a reset reads them). An episode follows
  // its seed to whichever row runs it, with one physics step per request and with three.
  Play({.envs = 4, .threads = 2, .reset_noise = 0.3, .engine_env = 2});
  Client c(ctx_, rpc());
  c.Hello();
  const auto run = [&](const Json& seeds, int n_steps) {
    const Json reset = c.Op("batch_reset", {{"seeds", seeds}});
    EXPECT_EQ(reset["op"], "batch_reset_ok") << reset.dump();
    std::vector<std::vector<double>> path{Unpack<double>(reset["obs"])};
    for (int i = 0; i < 12; ++i) {
      const double a = std::sin(0.3 * i);
      const Json r = Step(c, {a, a, a, a}, {{"n_steps", n_steps}});
      EXPECT_EQ(r["op"], "batch_step_ok") << r.dump();
      EXPECT_EQ(Unpack<std::uint32_t>(r["episode_steps"]),
                std::vector<std::uint32_t>(4, static_cast<std::uint32_t>((i + 1) * n_steps)));
      path.push_back(Unpack<double>(r["obs"]));
    }
    return path;
  };
  for (int n_steps : {1, 3}) {
    SCOPED_TRACE(::testing::Message() << "n_steps " << n_steps);
    const auto first = run(Json{7, 8, 9, 7}, n_steps);
    EXPECT_NE(first.back()[0], first.back()[3]);  // seeds 7 and 8 end apart
    EXPECT_NE(first.back()[6], first.back()[3]);  // 9 and 8 too
    const auto second = run(Json{9, 7, 7, 8}, n_steps);
    for (std::size_t s = 0; s < first.size(); ++s) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(first[s][k], first[s][9 + k]);       // seed 7: rows 0 and 3
        EXPECT_EQ(second[s][k], first[s][6 + k]);      // seed 9: row 0 now, row 2 (engine) before
        EXPECT_EQ(second[s][3 + k], first[s][k]);      // seed 7: row 1
        EXPECT_EQ(second[s][6 + k], first[s][k]);      // seed 7: the engine's row
        EXPECT_EQ(second[s][9 + k], first[s][3 + k]);  // seed 8: row 3 now, row 1 before
      }
    }
  }
}

TEST_F(StepServerBatchTest, EndedEpisodesResetAtTheNextStepUnlessAutoResetIsOff) {
  Play({.envs = 3, .threads = 2, .max_episode_steps = 6, .reset_noise = 0.1});
  Client c(ctx_, rpc());
  c.Hello();
  Json r = c.Op("batch_reset", {{"seed", 1}});
  const auto start = Unpack<double>(r["obs"]);
  for (int i = 1; i <= 3; ++i) {
    r = Step(c, {1, 1, 1}, {{"n_steps", 2}});
    ASSERT_EQ(r["op"], "batch_step_ok") << r.dump();
    EXPECT_EQ(Unpack<std::uint8_t>(r["done"]), std::vector<std::uint8_t>(3, i == 3 ? 1 : 0));
  }
  // The next step resets them (their actions ignored) and shows the first state of the next
  // episode (the generators went on: not the first episode's start).
  r = Step(c, {1, 1, 1});
  EXPECT_EQ(Unpack<std::uint8_t>(r["reset"]), std::vector<std::uint8_t>(3, 1));
  EXPECT_EQ(Unpack<std::uint8_t>(r["done"]), std::vector<std::uint8_t>(3, 0));
  EXPECT_EQ(Unpack<double>(r["time"]), std::vector<double>(3, 0.0));
  EXPECT_EQ(Unpack<std::uint32_t>(r["episode_steps"]), std::vector<std::uint32_t>(3, 0));
  EXPECT_NE(Unpack<double>(r["obs"])[0], start[0]);
  // A client's reset flags reset only those environments.
  r = Step(c, {1, 1, 1}, {{"reset", {false, true, false}}});
  EXPECT_EQ(Unpack<std::uint8_t>(r["reset"]), (std::vector<std::uint8_t>{0, 1, 0}));
  EXPECT_EQ(Unpack<std::uint32_t>(r["episode_steps"]), (std::vector<std::uint32_t>{1, 0, 1}));
  // Auto-reset off: an ended episode goes on (and stays done) until batch_reset.
  r = c.Op("batch_reset", {{"auto_reset", false}});
  ASSERT_EQ(r["auto_reset"], false);
  for (int i = 0; i < 4; ++i) r = Step(c, {0, 0, 0}, {{"n_steps", 2}});
  EXPECT_EQ(Unpack<std::uint8_t>(r["done"]), std::vector<std::uint8_t>(3, 1));
  r = Step(c, {0, 0, 0});
  EXPECT_EQ(Unpack<std::uint8_t>(r["reset"]), std::vector<std::uint8_t>(3, 0));
  EXPECT_EQ(Unpack<std::uint32_t>(r["episode_steps"]), std::vector<std::uint32_t>(3, 9));
}

TEST_F(StepServerBatchTest, ACancelledBatchStepLeavesNoJobForLaterSteps) {
  Play({.envs = 2, .threads = 2});
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("batch_reset")["op"], "batch_reset_ok");
  // A long batch step from a second socket of the same session (a DEALER: the first waits for
  // nothing), cancelled while its window runs.
  zmq::socket_t pipe(ctx_, zmq::socket_type::dealer);
  pipe.set(zmq::sockopt::linger, 0);
  pipe.set(zmq::sockopt::rcvtimeo, 60000);
  pipe.connect(rpc());
  const std::uint64_t before = manager_.session().engine().step_count();
  const std::vector<std::uint8_t> request = Json::to_msgpack(Json{{"op", "batch_step"},
                                                                  {"session_id", c.session()},
                                                                  {"actions", Packed({1, 1})},
                                                                  {"n_steps", 100000}});
  pipe.send(zmq::buffer(request));
  ASSERT_TRUE(urlab::testing::WaitFor(
      [&] { return manager_.session().engine().step_count() > before; }, 10000ms));
  const Json cancel = c.Op("cancel");
  ASSERT_EQ(cancel["op"], "cancel_ok") << cancel.dump();
  EXPECT_EQ(cancel["cancelled"], 1);
  zmq::message_t m;
  ASSERT_TRUE(pipe.recv(m));
  const Json cancelled = Json::from_msgpack(static_cast<const std::uint8_t*>(m.data()),
                                            static_cast<const std::uint8_t*>(m.data()) + m.size());
  EXPECT_EQ(cancelled["code"], "cancelled") << cancelled.dump();
  // Plain lockstep steps step environment 0 alone: the cancelled job is not theirs to finish.
  for (int i = 0; i < 3; ++i) ASSERT_EQ(c.Op("step")["op"], "step_ok");
  const Json r = Step(c, {0, 0});
  ASSERT_EQ(r["op"], "batch_step_ok") << r.dump();
  const auto time = Unpack<double>(r["time"]);
  EXPECT_NEAR(time[0] - time[1], 3 * 0.002, 1e-9);
  EXPECT_GT(time[1], 0.003);  // the cancelled window ran in both environments
}

TEST_F(StepServerBatchTest, AReplayIsRefusedWhileEnvironmentsStepTogether) {
  Play({.envs = 2});
  Client c(ctx_, rpc());
  c.Hello();
  const Json r = c.Op("replay_start", {{"mode", "resimulate"}});
  EXPECT_EQ(r["code"], "bad_mode") << r.dump();
  EXPECT_NE(r["message"].get<std::string>().find("--envs"), std::string::npos) << r.dump();
  EXPECT_EQ(Step(c, {0, 0})["op"], "batch_step_ok");  // the batch goes on
}

// A run of its own of `scene` (the pendulum) with `envs` environments and the batch's seed
// `seed` (`urlab run` gives it the scene's), driven for `steps` batch steps of one step each;
// every environment gets the action 4 sin(0.3 k) at step k. Returns the observations after each
// step (environment after environment).
std::vector<std::vector<double>> DriveRun(const std::string& dir, const std::string& scene,
                                          int envs, int steps, std::uint64_t seed) {
  world::Manager manager;
  auto* batch = &static_cast<world::BatchSubsystem&>(
      manager.AddSubsystem(std::make_unique<world::BatchSubsystem>(
          world::BatchSubsystemOptions{.envs = envs, .threads = 2, .seed = seed})));
  NetworkSubsystem* served =
      &urlab::testing::Serve(manager, dir, scene, urlab::testing::AutoPorts("direct"),
                             [&](NetworkSubsystem& net) { net.SetBatch(batch); });
  zmq::context_t ctx(1);
  std::vector<std::vector<double>> path;
  {
    Client c(ctx, served->endpoints().rpc);
    c.Hello();
    for (int k = 0; k < steps; ++k) {
      const std::vector<double> actions(static_cast<std::size_t>(envs), 4 * std::sin(0.3 * k));
      const Json r = c.Op("batch_step", {{"actions", Packed(actions)}});
      EXPECT_EQ(r["op"], "batch_step_ok") << r.dump();
      path.push_back(Unpack<double>(r["obs"]));
    }
  }
  manager.EndPlay();
  return path;
}

// Environment `env`'s observation row (3 values) of every step of a path.
std::vector<std::vector<double>> Rows(const std::vector<std::vector<double>>& path, int env) {
  std::vector<std::vector<double>> out;
  for (const auto& obs : path) {
    out.emplace_back(obs.begin() + 3 * env, obs.begin() + 3 * env + 3);
  }
  return out;
}

TEST_F(StepServerBatchTest, LatencyDelaysEveryEnvironmentAndEnvironmentZeroIsTheSingleRun) {
  const std::string plain = "seed: 5\narticulations:\n  - {name: pend, mjcf: pendulum.xml}\n";
  // A fixed observation delay first: every environment observes the undelayed run's state of 3
  // steps before (before any release: the state it started from).
  const std::string fixed =
      "seed: 5\narticulations:\n  - name: pend\n    mjcf: pendulum.xml\n    latency:\n"
      "      observation: {delay_steps: 3}\n";
  const auto undelayed = DriveRun(dir_, plain, 3, 40, 5);
  const auto delayed = DriveRun(dir_, fixed, 3, 40, 5);
  for (int env = 0; env < 3; ++env) {
    const auto rows = Rows(delayed, env), truth = Rows(undelayed, env);
    for (std::size_t k = 3; k < rows.size(); ++k) EXPECT_EQ(rows[k], truth[k - 3]) << k;
    EXPECT_EQ(rows[1][0], 0.0);  // the reset state (at rest, no noise) until the first release
  }
  // Jitter on both channels: environment 0 of a batched run is the single-environment run (the
  // same seed draws the same delays), bit for bit; the other environments draw their own.
  const std::string jittered =
      "seed: 5\narticulations:\n  - name: pend\n    mjcf: pendulum.xml\n    latency:\n"
      "      control: {delay_steps: 2, jitter_steps: 2}\n"
      "      observation: {delay_steps: 2, jitter_steps: 1}\n";
  const auto batched = DriveRun(dir_, jittered, 3, 60, 5);
  const auto single = DriveRun(dir_, jittered, 1, 60, 5);
  EXPECT_EQ(Rows(batched, 0), Rows(single, 0));
  EXPECT_NE(Rows(batched, 0), Rows(undelayed, 0));
  EXPECT_NE(Rows(batched, 1), Rows(batched, 0));
  EXPECT_NE(Rows(batched, 2), Rows(batched, 1));
  // The same seed draws the same delays again.
  EXPECT_EQ(DriveRun(dir_, jittered, 3, 60, 5), batched);
  // Environment i draws from the seed + i: environment 1 of seed 5 is environment 0 of seed 6.
  EXPECT_EQ(Rows(DriveRun(dir_, "seed: 6" + jittered.substr(7), 2, 60, 6), 0), Rows(batched, 1));
}

TEST_F(StepServerBatchTest, RandomizeDrawsAModelForEachEnvironmentAtEachReset) {
  // The pendulum's mass and damping drawn at each reset: the same torques swing each environment
  // differently. Environment 0 of a batched run is the single-environment run of the same seed.
  const std::string scene =
      "seed: 3\narticulations:\n  - {name: pend, mjcf: pendulum.xml}\n"
      "randomize:\n  pend:\n    mass: {uniform: [0.5, 2.0]}\n"
      "    damping: {uniform: [0.2, 3.0]}\n    qpos_noise: {uniform: [-0.2, 0.2]}\n"
      "    obs_noise: {uniform: [0.01, 0.05]}\n";
  const auto batched = DriveRun(dir_, scene, 3, 30, 3);
  EXPECT_NE(Rows(batched, 1), Rows(batched, 0));
  EXPECT_NE(Rows(batched, 2), Rows(batched, 1));
  EXPECT_NE(batched[0][0], batched[0][3]);  // qpos_noise: they start apart
  EXPECT_EQ(Rows(DriveRun(dir_, scene, 1, 30, 3), 0), Rows(batched, 0));
  EXPECT_EQ(DriveRun(dir_, scene, 3, 30, 3), batched);  // the same seed, the same draws
  const std::string other = "seed: 4" + scene.substr(7);
  EXPECT_NE(Rows(DriveRun(dir_, other, 3, 30, 4), 0), Rows(batched, 0));
  // Environment i draws from the seed + i: environment 1 of seed 3 is environment 0 of seed 4.
  EXPECT_EQ(Rows(DriveRun(dir_, other, 3, 30, 4), 0), Rows(batched, 1));

  // Each reset draws again; a reset seed restarts an environment's draws, whichever it is.
  Play({.envs = 3, .threads = 2}, "direct", scene);
  ASSERT_TRUE(manager_.session().randomizes());
  Client c(ctx_, rpc());
  c.Hello();
  const auto run = [&](const Json& reset) {
    const Json r0 = c.Op("batch_reset", reset);
    EXPECT_EQ(r0["op"], "batch_reset_ok") << r0.dump();
    std::vector<std::vector<double>> path{Unpack<double>(r0["obs"])};
    for (int k = 0; k < 20; ++k) {
      path.push_back(Unpack<double>(Step(c, {1.5, 1.5, 1.5})["obs"]));
    }
    return path;
  };
  const auto first = run({{"seeds", {11, 12, 11}}});
  EXPECT_EQ(Rows(first, 0), Rows(first, 2));  // seed 11 in environments 0 and 2
  for (int env = 0; env < 3; ++env) {
    EXPECT_NE(first[0][3 * env + 1], 0.0);  // at rest after the reset, observed with noise
  }
  EXPECT_NE(Rows(first, 0), Rows(first, 1));
  const auto again = run({{"seeds", {12, 11, 11}}});
  EXPECT_EQ(Rows(again, 1), Rows(first, 0));  // seed 11 now in environment 1
  EXPECT_EQ(Rows(again, 0), Rows(first, 1));  // seed 12 in environment 0 (the engine's)
  const auto unseeded = run(Json::object());  // the streams go on: new draws
  EXPECT_NE(Rows(unseeded, 1), Rows(again, 1));
}

TEST_F(StepServerBatchTest, APdSceneTakesJointTargetsInEveryEnvironment) {
  // The pendulum with a joint range under the scene's PD controller: the actions are targets.
  std::string xml = kPendulumXml;
  xml.replace(xml.find("damping=\"0.05\""), 14, "damping=\"0.05\" range=\"-2 1.5\"");
  xml.replace(xml.find("<option"), 0, "<compiler angle=\"radian\"/>\n  ");
  urlab::testing::WriteTextFile(dir_, "limited.xml", xml);
  Play({.envs = 3, .threads = 2}, "direct",
       "articulations:\n  - {name: pend, mjcf: limited.xml, controller: {type: pd, kp: 60, kv: "
       "4}}\n");
  Client c(ctx_, rpc());
  c.Hello();
  const Json info = c.Op("batch_info");
  EXPECT_EQ(Unpack<double>(info["action_low"]), std::vector<double>{-2});  // the joint's range
  EXPECT_EQ(Unpack<double>(info["action_high"]), std::vector<double>{1.5});
  Json r;
  for (int i = 0; i < 50; ++i) r = Step(c, {0.4, -0.6, 0.4}, {{"n_steps", 20}});
  ASSERT_EQ(r["op"], "batch_step_ok") << r.dump();
  const auto obs = Unpack<double>(r["obs"]);
  // Environment 0 (the engine's, its controllers the batch's own) and 2 (the batch's) agree bit
  // for bit; each pendulum holds near its target against gravity (a raw torque of 0.4 would
  // have swung it round).
  for (int k = 0; k < 3; ++k) EXPECT_EQ(obs[k], obs[6 + k]);
  EXPECT_NEAR(obs[0], 0.4, 0.05);
  EXPECT_NEAR(obs[3], -0.6, 0.05);
  EXPECT_NEAR(obs[1], 0.0, 1e-3);  // at rest
  // A reset starts every environment's controllers afresh: the same episode again.
  c.Op("batch_reset", {{"seed", 3}});
  Json again;
  for (int i = 0; i < 50; ++i) again = Step(c, {0.4, -0.6, 0.4}, {{"n_steps", 20}});
  c.Op("batch_reset", {{"seed", 3}});
  Json third;
  for (int i = 0; i < 50; ++i) third = Step(c, {0.4, -0.6, 0.4}, {{"n_steps", 20}});
  EXPECT_EQ(Unpack<double>(again["obs"]), Unpack<double>(third["obs"]));
}

TEST_F(StepServerBatchTest, RawActionsAreTheControlsWithTheControllersOff) {
  std::string xml = kPendulumXml;
  xml.replace(xml.find("damping=\"0.05\""), 14, "damping=\"0.05\" range=\"-2 1.5\"");
  xml.replace(xml.find("<option"), 0, "<compiler angle=\"radian\"/>\n  ");
  urlab::testing::WriteTextFile(dir_, "limited.xml", xml);
  Play({.envs = 2, .threads = 2, .raw_actions = true}, "direct",
       "articulations:\n  - {name: pend, mjcf: limited.xml, controller: {type: pd, kp: 60, kv: "
       "4}}\n");
  Client c(ctx_, rpc());
  c.Hello();
  const Json info = c.Op("batch_info");
  EXPECT_EQ(Unpack<double>(info["action_low"]), std::vector<double>{-5});  // the ctrlrange
  EXPECT_EQ(Unpack<double>(info["action_high"]), std::vector<double>{5});
  Json r;
  for (int i = 0; i < 10; ++i) r = Step(c, {0.0, 0.0}, {{"n_steps", 20}});
  const auto obs = Unpack<double>(r["obs"]);
  // No PD holds them: both pendulums fall under gravity alike, far from any target.
  EXPECT_EQ(obs[0], obs[3]);
  EXPECT_GT(obs[0], 0.3);
}

TEST_F(StepServerBatchTest, OneEnvironmentIsTheEngineAlone) {
  Play({.envs = 1});
  Client c(ctx_, rpc());
  c.Hello();
  const Json info = c.Op("batch_info");
  EXPECT_EQ(info["envs"], 1);
  const Json r = Step(c, {2.0}, {{"n_steps", 5}});
  ASSERT_EQ(r["op"], "batch_step_ok") << r.dump();
  EXPECT_EQ(Unpack<double>(r["obs"]).size(), 3u);
  EXPECT_NEAR(Unpack<double>(r["time"])[0], 0.01, 1e-12);
  EXPECT_EQ(manager_.session().engine().step_count(), 5u);
}

}  // namespace
}  // namespace urlab::net::tests
