// The step server against hostile or careless clients (the security review's network cases):
// real sockets on loopback, a real Manager; each case checks that the process keeps serving,
// that nothing is applied or written, and that the error or counter is the right one.
#include <gtest/gtest.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>
#include <zmq.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"
#include "support/wait.h"
#include "urlab/replay/recorder.h"
#include "wire/shm_channel.h"

// A namespace of their own: their plain nlohmann::json alias must not meet net::Json (the
// ordered one) where a unity build puts several test files in one translation unit.
namespace urlab::net::tests {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Json = nlohmann::json;
using test_client::Client;
using urlab::testing::WaitFor;

// A free base with an arm: a quaternion in qpos, a joint, an actuator.
constexpr const char* kBotXml = R"(<mujoco model="bot">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1"/>
    <body name="base" pos="0 0 0.5">
      <freejoint name="root"/>
      <geom type="box" size="0.1 0.1 0.1" mass="2"/>
      <body name="link" pos="0.1 0 0">
        <joint name="hinge" type="hinge" axis="0 1 0" damping="0.5"/>
        <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
</mujoco>
)";

constexpr const char* kHumanoid = URLAB_SOURCE_DIR "/examples/models/humanoid.xml";

// Every line logged while it is installed.
class LogLines : public spdlog::sinks::base_sink<std::mutex> {
 public:
  std::size_t Count(const std::string& part) {
    std::lock_guard<std::mutex> lock(mutex_);
    return static_cast<std::size_t>(
        std::count_if(lines_.begin(), lines_.end(),
                      [&](const std::string& l) { return l.find(part) != std::string::npos; }));
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    lines_.emplace_back(msg.payload.data(), msg.payload.size());
  }
  void flush_() override {}

 private:
  std::vector<std::string> lines_;
};

struct PlayOptions {
  std::string mjcf = "bot.xml";
  std::string mode = "live";
  std::string files_dir;  // "" : the fixture's files/ folder
  bool recorder = false;
  std::size_t max_queued_steps = 100000;
  std::string state = "tcp://127.0.0.1:*", rpc = "tcp://127.0.0.1:*";
  std::string shm_dir;  // "": /dev/shm
};

class StepServerHardeningTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override {
    urlab::testing::WriteTextFile(dir_, "bot.xml", kBotXml);
    files_ = dir_ + "/files";
    log_ = std::make_shared<LogLines>();
    spdlog::default_logger()->sinks().push_back(log_);
    level_ = spdlog::default_logger()->level();
    spdlog::default_logger()->set_level(spdlog::level::info);
  }
  void TearDown() override {
    manager_.EndPlay();
    auto& sinks = spdlog::default_logger()->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), log_), sinks.end());
    spdlog::default_logger()->set_level(level_);
    MujocoTest::TearDown();
  }
  void Play(const PlayOptions& p = {}) {
    replay::RecorderSubsystem* recorder = nullptr;
    if (p.recorder) {
      recorder = &static_cast<replay::RecorderSubsystem&>(
          manager_.AddSubsystem(std::make_unique<replay::RecorderSubsystem>()));
    }
    NetworkOptions o = urlab::testing::AutoPorts(p.mode);
    o.state = p.state;
    o.rpc = p.rpc;
    o.files_dir = p.files_dir.empty() ? files_ : p.files_dir;
    o.max_queued_steps = p.max_queued_steps;
    o.shm_dir = p.shm_dir;
    Serve("control_source: network\narticulations:\n  - {name: bot, mjcf: " + p.mjcf + "}\n", o,
          [&](NetworkSubsystem& net) { net.SetRecorder(recorder); });
  }
  physics::PhysicsEngine& engine() { return manager_.session().engine(); }

  std::string files_;
  std::shared_ptr<LogLines> log_;
  spdlog::level::level_enum level_ = spdlog::level::info;
};

// A DEALER client: several requests in flight for one session.
class Pipeline {
 public:
  Pipeline(zmq::context_t& ctx, const std::string& endpoint) : s_(ctx, zmq::socket_type::dealer) {
    s_.set(zmq::sockopt::linger, 0);
    s_.set(zmq::sockopt::rcvtimeo, 60000);
    s_.connect(endpoint);
  }
  void Send(const Json& request) {
    const std::vector<std::uint8_t> bytes = Json::to_msgpack(request);
    s_.send(zmq::buffer(bytes));
  }
  Json Receive() {
    zmq::message_t m;
    if (!s_.recv(m)) return Json{{"op", "timeout"}};
    const auto* b = static_cast<const std::uint8_t*>(m.data());
    return Json::from_msgpack(b, b + m.size());
  }

 private:
  zmq::socket_t s_;
};

// A JSON text request, sent as it is; the reply parsed ("timeout" when none came).
Json RawJson(zmq::context_t& ctx, const std::string& endpoint, const std::string& text) {
  zmq::socket_t s(ctx, zmq::socket_type::req);
  s.set(zmq::sockopt::linger, 0);
  s.set(zmq::sockopt::rcvtimeo, 10000);
  s.connect(endpoint);
  s.send(zmq::buffer(text));
  zmq::message_t m;
  if (!s.recv(m)) return Json{{"op", "timeout"}};
  return Json::parse(m.to_string_view());
}

// Issue case 1: a JSON `seq` nested 20,000 deep (40 KB, under the size limit) used to crash the
// server when the reply echoed it. It is refused like msgpack's; the limit is the same for both.
TEST_F(StepServerHardeningTest, DeeplyNestedJsonIsRefusedAndTheServerGoesOn) {
  Play();
  const std::string deep =
      R"({"op": "hello", "seq": )" + std::string(20000, '[') + std::string(20000, ']') + "}";
  ASSERT_LT(deep.size(), 1u << 20);
  const Json r = RawJson(ctx_, rpc(), deep);
  EXPECT_EQ(r["code"], "bad_request") << r.dump().substr(0, 200);
  EXPECT_NE(r.value("message", "").find("nested"), std::string::npos) << r.dump();
  // The limit, exactly: the request map plus 31 levels of seq is 32 deep and is echoed.
  const auto nested = [](int levels) {
    return std::string(static_cast<std::size_t>(levels), '[') + "1" +
           std::string(static_cast<std::size_t>(levels), ']');
  };
  const Json ok = RawJson(ctx_, rpc(), R"({"op": "meta", "seq": )" + nested(31) + "}");
  EXPECT_EQ(ok["op"], "meta_ok") << ok.dump().substr(0, 200);
  EXPECT_EQ(RawJson(ctx_, rpc(), R"({"op": "meta", "seq": )" + nested(32) + "}")["code"],
            "bad_request");
  // Brackets inside strings are text, not nesting.
  const Json text =
      RawJson(ctx_, rpc(), R"({"op": "meta", "seq": ")" + std::string(100, '[') + R"(\"]"})");
  EXPECT_EQ(text["op"], "meta_ok") << text.dump().substr(0, 200);
  // msgpack: the same limit.
  Client c(ctx_, rpc());
  std::string packed = "\x82\xa2op\xa5hello\xa3seq";
  packed += std::string(20000, '\x91') + "\x01";
  EXPECT_EQ(c.CallRaw(packed)["code"], "bad_request");
  EXPECT_EQ(c.Hello()["op"], "hello_ok");
}

// Issue case 16: a request that fails takes no lease (nor the lease of a live driver with force).
TEST_F(StepServerHardeningTest, AFailingRequestTakesNoLease) {
  Play({.mode = "direct"});
  Client a(ctx_, rpc()), b(ctx_, rpc());
  a.Hello();
  b.Hello();
  EXPECT_EQ(b.Op("set_mode", {{"mode", "warp"}})["code"], "bad_mode");
  EXPECT_TRUE(b.Op("get_counters")["driver"].is_null()) << "a refused set_mode took the lease";
  ASSERT_EQ(a.Op("step")["op"], "step_ok");
  EXPECT_EQ(b.Op("step", {{"force", true}, {"n_steps", 0}})["code"], "bad_value");
  EXPECT_EQ(b.Op("set_sim_options", {{"force", true}, {"options", {{"impratio", -1}}}})["code"],
            "bad_value");
  EXPECT_EQ(b.Op("get_counters")["driver"], a.session());
  EXPECT_EQ(a.Op("step")["op"], "step_ok");                     // still the driver
  ASSERT_EQ(b.Op("step", {{"force", true}})["op"], "step_ok");  // a good request takes it
  EXPECT_EQ(a.Op("step")["code"], "not_driver");
}

// Issue case 12: numbers outside their range are refused naming the field and the range, and
// nothing of the request is applied.
TEST_F(StepServerHardeningTest, OutOfRangeValuesAreRefusedWhole) {
  Play({.mode = "direct"});
  Client c(ctx_, rpc());
  c.Hello();
  const double timestep = engine().timestep();
  const auto refused = [&](const Json& options, const std::string& field,
                           const std::string& range) {
    const Json r = c.Op("set_sim_options", {{"options", options}});
    EXPECT_EQ(r["code"], "bad_value") << options.dump() << " -> " << r.dump();
    const std::string m = r.value("message", "");
    EXPECT_NE(m.find(field), std::string::npos) << m;
    EXPECT_NE(m.find(range), std::string::npos) << m;
  };
  // Each with a good timestep beside it: the good field is not applied either.
  refused({{"timestep", 0.001}, {"impratio", -1}}, "impratio", "(0, 1e+06]");
  refused({{"timestep", 0.001}, {"tolerance", -1e-8}}, "tolerance", "[0, 1]");
  refused({{"timestep", 0.001}, {"density", -1.2}}, "density", "[0, 1e+06]");
  refused({{"timestep", 0.001}, {"viscosity", -0.1}}, "viscosity", "[0, 1e+06]");
  refused({{"timestep", 0.001}, {"iterations", 2.5}}, "iterations", "an integer in [1, 10000]");
  refused({{"timestep", 0.001}, {"gravity", {0, 0, 1e300}}}, "gravity", "[-1e+06, 1e+06]");
  refused({{"timestep", 2.0}}, "timestep", "(0, 1]");
  EXPECT_EQ(c.Op("forward")["op"], "forward_ok");
  EXPECT_EQ(engine().timestep(), timestep);
  manager_.session().engine().WithLockedData([](const mjModel* m, mjData*) {
    EXPECT_EQ(m->opt.impratio, 1.0);
    EXPECT_EQ(m->opt.density, 0.0);
    EXPECT_EQ(m->opt.iterations, 100);
  });
  // A zero quaternion for the free joint: set_qpos (the base's 7 values, or all 8) and reset.
  const Json before = c.Op("forward");
  const Json qpos0 = before["per_articulation"]["bot"]["qpos"];
  Json r = c.Op("set_qpos", {{"articulation", "bot"}, {"qpos", {0, 0, 1, 0, 0, 0, 0}}});
  EXPECT_EQ(r["code"], "bad_value") << r.dump();
  EXPECT_NE(r.value("message", "").find("quaternion"), std::string::npos) << r.dump();
  EXPECT_EQ(
      c.Op("set_qpos", {{"articulation", "bot"}, {"qpos", {0, 0, 1, 0, 0, 0, 0, 0.3}}})["code"],
      "bad_value");
  r = c.Op("reset", {{"per_articulation_qpos", {{"bot", {{"root", {0, 0, 1, 0, 0, 0, 0}}}}}}});
  EXPECT_EQ(r["code"], "bad_value") << r.dump();
  EXPECT_EQ(
      c.Op("set_qpos", {{"articulation", "bot"}, {"qpos", {1e300, 0, 1, 1, 0, 0, 0}}})["code"],
      "bad_value");
  const Json after = c.Op("forward");
  EXPECT_EQ(after["per_articulation"]["bot"]["qpos"], qpos0);
  EXPECT_EQ(after["time"], before["time"]);  // no reset happened either
  // Unit quaternions (and slightly off ones) are fine.
  r = c.Op("set_qpos", {{"articulation", "bot"}, {"qpos", {0, 0, 1, 0.7071, 0, 0, 0.7071}}});
  EXPECT_EQ(r["op"], "set_qpos_ok") << r.dump();
  // Puppet mode's time.
  ASSERT_EQ(c.Op("set_mode", {{"mode", "puppet"}})["op"], "set_mode_ok");
  for (const double t : {-5.0, 1e300}) {
    r = c.Op("step", {{"time", t}});
    EXPECT_EQ(r["code"], "bad_value") << t;
    EXPECT_NE(r.value("message", "").find("time must be in [0, 1e+09]"), std::string::npos)
        << r.dump();
  }
  EXPECT_EQ(c.Op("step", {{"qpos", {0, 0, 1, 0, 0, 0, 0, 0}}})["code"], "bad_value");
  EXPECT_EQ(c.Op("forward")["time"], after["time"]);
  EXPECT_EQ(c.Op("step", {{"time", 3.5}})["time"], 3.5);
}

// Issue 38, case 8: a session forgotten to make room for a later hello (64 sessions at most)
// takes its shared-memory channel with it. The channels used to stay open at the cap, so no
// client was offered shared memory again.
TEST_F(StepServerHardeningTest, ChannelsOfEvictedSessionsAreReleased) {
  const std::string shm_dir = dir_ + "/shm";
  fs::create_directories(shm_dir);
  Play({.shm_dir = shm_dir});
  std::vector<std::unique_ptr<Client>> clients;
  std::vector<wire::ShmChannel> channels;
  for (int i = 0; i < 70; ++i) {
    clients.push_back(std::make_unique<Client>(ctx_, rpc()));
    const Json r = clients.back()->Hello({{"shm", true}});
    ASSERT_EQ(r["op"], "hello_ok") << r.dump();
    ASSERT_TRUE(r.contains("shm")) << "hello " << i << " got no shared-memory channel";
    channels.push_back(
        wire::ShmChannel::Attach(r["shm"]["path"], r["shm"]["generation"].get<std::uint64_t>()));
  }
  // The first six sessions were forgotten: their channels are closed by the server.
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(channels[i].PeerGone()) << i;
  EXPECT_FALSE(channels.back().PeerGone());
}

// Issue 38, case 2: a randomised reset's ranges are checked when the request is parsed (a
// negative mass, armature or damping, gravity 1e308 used to get reset_ok and stop the run).
TEST_F(StepServerHardeningTest, RandomisationRangesAreCheckedInTheRequest) {
  Play({.mode = "direct"});
  Client c(ctx_, rpc());
  c.Hello();
  const auto refused = [&](const Json& randomize, const std::string& field,
                           const std::string& range) {
    const Json r = c.Op("reset", {{"seed", 1}, {"randomize", randomize}});
    EXPECT_EQ(r["code"], "bad_value") << randomize.dump() << " -> " << r.dump();
    const std::string m = r.value("message", "");
    EXPECT_NE(m.find(field), std::string::npos) << m;
    EXPECT_NE(m.find(range), std::string::npos) << m;
  };
  refused({{"bot", {{"mass", {{"uniform", {-2, -1}}}}}}}, "randomize.bot.mass", "[0.001, 1000]");
  refused({{"bot", {{"armature", {{"uniform", {-5, -1}}}}}}}, "randomize.bot.armature",
          "[0, 1000]");
  refused({{"bot", {{"damping", {{"normal", {-3, 1}}}}}}}, "randomize.bot.damping", "[0, 1000]");
  refused({{"gravity", {{"z", {{"uniform", {1e308, 1e308}}}}}}}, "randomize.gravity.z",
          "[-100, 100]");
  const Json ok =
      c.Op("reset", {{"seed", 1}, {"randomize", {{"bot", {{"mass", {{"uniform", {0.5, 2}}}}}}}}});
  EXPECT_EQ(ok["op"], "reset_ok") << ok.dump();
}

// Issue 38, case 3: a latency setting whose ticks would size a huge buffer (rate_hz 1e-5 took
// 1.6 GB; 1e-6: std::bad_alloc) is refused naming the channel, the field and the limit.
TEST_F(StepServerHardeningTest, LatencySettingsAreBounded) {
  Play({.mode = "direct"});
  Client c(ctx_, rpc());
  c.Hello();
  // One value every 1,500,000 steps at 2 ms: 64 MB of control slots before the bound.
  Json r = c.Op("set_latency", {{"articulation", "bot"}, {"control", {{"rate_hz", 1.0 / 3000}}}});
  EXPECT_EQ(r["code"], "bad_value") << r.dump();
  std::string m = r.value("message", "");
  EXPECT_NE(m.find("control"), std::string::npos) << m;
  EXPECT_NE(m.find("rate_hz"), std::string::npos) << m;
  EXPECT_NE(m.find("at most 1000000 steps"), std::string::npos) << m;
  r = c.Op("set_latency", {{"articulation", "bot"},
                           {"observation", {{"delay_steps", 600000}, {"jitter_steps", 600000}}}});
  EXPECT_EQ(r["code"], "bad_value") << r.dump();
  EXPECT_NE(r.value("message", "").find("observation"), std::string::npos) << r.dump();
  r = c.Op("set_latency", {{"articulation", "bot"}, {"control", {{"rate_hz", 50}}}});
  EXPECT_EQ(r["op"], "set_latency_ok") << r.dump();
}

// Issue 38, case 9: `arrays` in hello is "binary" or "list"; anything else (a 2026 hello with
// "hex" was accepted as lists) is bad_value naming the field.
TEST_F(StepServerHardeningTest, HelloArraysIsBinaryOrList) {
  Play();
  for (const Json& hello :
       {Json{{"arrays", "hex"}}, Json{{"arrays", "hex"}, {"client_version", "urlab_bridge/1.0"}}}) {
    Client c(ctx_, rpc());
    const Json r = c.Hello(hello);
    EXPECT_EQ(r["code"], "bad_value") << r.dump();
    EXPECT_NE(r.value("message", "").find("arrays"), std::string::npos) << r.dump();
    EXPECT_NE(r.value("message", "").find("binary or list"), std::string::npos) << r.dump();
  }
  for (const char* arrays : {"binary", "list"}) {
    Client c(ctx_, rpc());
    EXPECT_EQ(c.Hello({{"arrays", arrays}})["op"], "hello_ok") << arrays;
  }
}

// Issue case 3: clients name files, never paths; only under the files folder; never over an
// existing file without overwrite and the lease; never over an input of the running scene.
TEST_F(StepServerHardeningTest, FilesAreNamesUnderTheFilesFolder) {
  Play({.recorder = true});
  Client a(ctx_, rpc()), observer(ctx_, rpc());
  a.Hello();
  observer.Hello();
  const std::string mjcf = urlab::testing::ReadTextFile(dir_ + "/bot.xml");
  for (const std::string& bad :
       {dir_ + "/bot.xml", std::string("../bot.xml"), std::string(".."), std::string(".x"),
        std::string(""), std::string("a/b"), std::string("x\ny")}) {
    const Json r = observer.Op("snapshot_save", {{"path", bad}});
    EXPECT_EQ(r["code"], "bad_file_name") << bad << " -> " << r.dump();
    EXPECT_EQ(observer.Op("recording_save", {{"path", bad}})["code"], "bad_file_name") << bad;
    EXPECT_EQ(a.Op("snapshot_load", {{"path", bad}})["code"], "bad_file_name") << bad;
    EXPECT_EQ(a.Op("replay_load", {{"path", bad}})["code"], "bad_file_name") << bad;
  }
  EXPECT_EQ(a.Op("replay_load", {{"path", "/etc/passwd"}})["code"], "bad_file_name");
  EXPECT_EQ(urlab::testing::ReadTextFile(dir_ + "/bot.xml"), mjcf);
  // A name: written under the files folder (made when missing).
  const Json saved = observer.Op("snapshot_save", {{"path", "state.urrec"}});
  ASSERT_EQ(saved["op"], "snapshot_save_ok") << saved.dump();
  EXPECT_EQ(saved["path"], files_ + "/state.urrec");
  ASSERT_TRUE(fs::is_regular_file(files_ + "/state.urrec"));
  const auto size = fs::file_size(files_ + "/state.urrec");
  // Existing: refused unless overwrite, which needs the lease.
  EXPECT_EQ(observer.Op("snapshot_save", {{"path", "state.urrec"}})["code"], "file_exists");
  ASSERT_EQ(a.Op("step")["op"], "step_ok");  // a drives
  EXPECT_EQ(observer.Op("snapshot_save", {{"path", "state.urrec"}, {"overwrite", true}})["code"],
            "not_driver");
  EXPECT_EQ(a.Op("snapshot_save", {{"path", "state.urrec"}, {"overwrite", true}})["op"],
            "snapshot_save_ok");
  EXPECT_EQ(a.Op("snapshot_load", {{"path", "state.urrec"}})["op"], "snapshot_load_ok");
  EXPECT_EQ(a.Op("recording_save", {{"path", "x.urrec.part"}})["code"], "bad_file_name");
  EXPECT_GT(size, 0u);
  // A link in the folder to the scene's MJCF: never written through.
  fs::create_symlink(dir_ + "/bot.xml", files_ + "/link.urrec");
  const Json link = a.Op("snapshot_save", {{"path", "link.urrec"}, {"overwrite", true}});
  EXPECT_EQ(link["code"], "file_is_input") << link.dump();
  EXPECT_EQ(urlab::testing::ReadTextFile(dir_ + "/bot.xml"), mjcf);
}

// Issue case 3, the scene's own inputs: with the files folder set to the scene's folder, its
// scene and MJCF files are refused even with overwrite and the lease.
TEST_F(StepServerHardeningTest, TheScenesInputsAreNeverWritten) {
  urlab::testing::WriteTextFile(dir_, "scene.yaml", "# the scene file\n");
  Play({.files_dir = dir_, .recorder = true});
  Client a(ctx_, rpc());
  a.Hello();
  const std::string mjcf = urlab::testing::ReadTextFile(dir_ + "/bot.xml");
  for (const char* op : {"snapshot_save", "recording_save"}) {
    const Json r = a.Op(op, {{"path", "bot.xml"}, {"overwrite", true}});
    EXPECT_EQ(r["code"], "file_is_input") << op << ": " << r.dump();
  }
  EXPECT_EQ(a.Op("recording_start", {{"path", "bot.xml"}, {"overwrite", true}})["code"],
            "file_is_input");
  EXPECT_EQ(a.Op("snapshot_save", {{"path", "scene.yaml"}, {"overwrite", true}})["code"],
            "file_is_input");
  EXPECT_EQ(urlab::testing::ReadTextFile(dir_ + "/bot.xml"), mjcf);
}

// Issue case 3, FIFO: recording_start to a name whose .part is a FIFO used to block the I/O
// thread (every client timed out). It is refused at once; other clients are answered.
TEST_F(StepServerHardeningTest, AFifoWhereARecordingWouldGoIsRefused) {
  Play({.recorder = true});
  fs::create_directories(files_);
  ASSERT_EQ(::mkfifo((files_ + "/trap.urrec.part").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((files_ + "/trap2.urrec").c_str(), 0600), 0);
  Client a(ctx_, rpc()), observer(ctx_, rpc());
  a.Hello();
  observer.Hello();
  Json r = a.Op("recording_start", {{"path", "trap.urrec"}});
  EXPECT_EQ(r["code"], "path_not_writable") << r.dump();
  EXPECT_NE(r.value("message", "").find("FIFO"), std::string::npos) << r.dump();
  EXPECT_EQ(a.Op("snapshot_save", {{"path", "trap2.urrec"}, {"overwrite", true}})["code"],
            "path_not_writable");
  EXPECT_EQ(a.Op("replay_load", {{"path", "trap2.urrec"}})["code"], "path_not_readable");
  EXPECT_EQ(observer.Op("list_keyframes")["op"], "list_keyframes_ok");
  EXPECT_EQ(a.Op("recording_status")["active"], false);
}

// Issue case 9: a driver cannot queue unbounded lockstep work; set_mode with force cancels the
// old driver's queued steps (answered `cancelled`) and takes effect at once; `cancel` cancels
// one's own; observers are answered meanwhile.
TEST_F(StepServerHardeningTest, QueuedStepsAreBoundedAndCancellable) {
  Play({.mjcf = kHumanoid, .mode = "direct", .max_queued_steps = 300000});
  Client a(ctx_, rpc()), b(ctx_, rpc()), observer(ctx_, rpc());
  a.Hello({{"observations", "minimal"}});
  b.Hello({{"observations", "minimal"}});
  observer.Hello();
  Pipeline pipe(ctx_, rpc());
  const std::uint64_t start = engine().step_count();
  for (int i = 1; i <= 3; ++i) {
    pipe.Send({{"op", "step"}, {"session_id", a.session()}, {"seq", i}, {"n_steps", 100000}});
  }
  pipe.Send({{"op", "step"}, {"session_id", a.session()}, {"seq", 4}, {"n_steps", 1}});
  const Json full = pipe.Receive();  // answered at once, before the queued ones
  EXPECT_EQ(full["seq"], 4) << full.dump();
  EXPECT_EQ(full["code"], "queue_full") << full.dump();
  // Observers are answered while the work is queued.
  EXPECT_EQ(observer.Op("list_keyframes")["op"], "list_keyframes_ok");
  EXPECT_EQ(observer.Op("get_counters")["driver"], a.session());
  // b takes over with a forced set_mode: a's queued steps are cancelled, not waited for.
  const Json mode = b.Op("set_mode", {{"mode", "live"}, {"force", true}});
  ASSERT_EQ(mode["op"], "set_mode_ok") << mode.dump();
  EXPECT_EQ(mode["cancelled"], 3);
  for (int i = 1; i <= 3; ++i) {
    const Json r = pipe.Receive();
    EXPECT_EQ(r["seq"], i);
    EXPECT_EQ(r["code"], "cancelled") << r.dump();
  }
  EXPECT_LT(engine().step_count() - start, 300000u);  // the queue did not run to its end
  EXPECT_EQ(b.Op("get_counters")["driver"], b.session());
  EXPECT_EQ(b.Op("get_counters")["errors"]["cancelled"], 3);
  // `cancel`: a driver cancels its own queue.
  ASSERT_EQ(b.Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  const std::uint64_t before = engine().step_count();
  for (int i = 5; i <= 6; ++i) {
    pipe.Send({{"op", "step"}, {"session_id", b.session()}, {"seq", i}, {"n_steps", 100000}});
  }
  ASSERT_TRUE(WaitFor([&] { return engine().step_count() > before; }, 10000ms));
  const Json cancel = b.Op("cancel");
  ASSERT_EQ(cancel["op"], "cancel_ok") << cancel.dump();
  EXPECT_EQ(cancel["cancelled"], 2);
  EXPECT_EQ(pipe.Receive()["code"], "cancelled");
  EXPECT_EQ(pipe.Receive()["code"], "cancelled");
  EXPECT_LT(engine().step_count() - before, 200000u);
  const Json step = b.Op("step", {{"n_steps", 3}});  // lockstep goes on exactly
  ASSERT_EQ(step["op"], "step_ok") << step.dump();
  EXPECT_EQ(b.Op("step")["step"].get<std::uint64_t>(), step["step"].get<std::uint64_t>() + 1);
}

// Issue case 14b: replay sessions do not pile up: a client's new load releases its earlier one,
// losing the lease or saying bye releases them, replay_unload releases one.
TEST_F(StepServerHardeningTest, ReplaySessionsAreReleased) {
  Play({.recorder = true});
  Client a(ctx_, rpc()), b(ctx_, rpc()), observer(ctx_, rpc());
  a.Hello();
  b.Hello();
  observer.Hello();
  ASSERT_EQ(a.Op("recording_start", {{"path", "run.urrec"}})["op"], "recording_start_ok");
  ASSERT_TRUE(WaitFor([&] { return a.Op("recording_status")["frames"] > 10; }));
  ASSERT_EQ(a.Op("recording_stop")["op"], "recording_stop_ok");
  for (int i = 0; i < 30; ++i) {
    const Json r = a.Op("replay_load", {{"path", "run.urrec"}});
    ASSERT_EQ(r["op"], "replay_load_ok") << r.dump();
  }
  Json list = observer.Op("replay_list_sessions");
  ASSERT_EQ(list["sessions"].size(), 1u) << list.dump();
  EXPECT_EQ(list["active"], "r30");
  // b takes the lease: a's recordings go with it.
  ASSERT_EQ(b.Op("replay_load", {{"path", "run.urrec"}, {"force", true}})["op"], "replay_load_ok");
  list = observer.Op("replay_list_sessions");
  ASSERT_EQ(list["sessions"].size(), 1u) << list.dump();
  EXPECT_EQ(list["active"], "r31");
  ASSERT_EQ(b.Op("replay_start")["op"], "replay_start_ok");
  const Json unload = b.Op("replay_unload");
  EXPECT_EQ(unload["op"], "replay_unload_ok") << unload.dump();
  EXPECT_EQ(observer.Op("replay_status")["active"], false);  // its playback stopped with it
  EXPECT_EQ(observer.Op("replay_list_sessions")["sessions"].size(), 0u);
  EXPECT_EQ(b.Op("replay_unload")["code"], "replay_session_not_found");
  ASSERT_EQ(b.Op("replay_load", {{"path", "run.urrec"}})["op"], "replay_load_ok");
  ASSERT_EQ(b.Op("bye")["op"], "bye_ok");
  EXPECT_EQ(observer.Op("replay_list_sessions")["sessions"].size(), 0u);
}

// Issue case 7: lease takeovers do not flood the log (two clients forcing each other).
TEST_F(StepServerHardeningTest, LeaseTakeoversAreLoggedAtMostOnceASecond) {
  Play({.mode = "live"});
  Client a(ctx_, rpc()), b(ctx_, rpc());
  a.Hello();
  b.Hello();
  const auto t0 = std::chrono::steady_clock::now();
  constexpr int kRounds = 300;
  for (int i = 0; i < kRounds; ++i) {
    ASSERT_EQ(a.Op("step", {{"force", true}})["op"], "step_ok");
    ASSERT_EQ(b.Op("step", {{"force", true}})["op"], "step_ok");
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::size_t lines = log_->Count("took the lease");
  EXPECT_GE(lines, 1u);
  EXPECT_LE(static_cast<double>(lines), 1.0 + std::ceil(seconds))
      << lines << " lines for " << 2 * kRounds - 1 << " takeovers";
}

// Issue case 16: sockets bound beyond loopback are logged (docs/network.md says so).
TEST_F(StepServerHardeningTest, SocketsBeyondLoopbackAreLogged) {
  Play({.state = "tcp://*:*", .rpc = "tcp://0.0.0.0:*"});
  EXPECT_EQ(log_->Count("step server: tcp://0.0.0.0:* accepts requests from other hosts"), 1u);
  EXPECT_EQ(log_->Count("the state socket publishes to other hosts"), 1u);
  EXPECT_EQ(log_->Count("the control socket"), 0u);  // loopback: nothing to say
}

}  // namespace
}  // namespace urlab::net::tests
