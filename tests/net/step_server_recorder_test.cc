// The step server's recorder, snapshot and replay operations against a real Manager with a
// recorder subsystem and real sockets (a REQ client speaking msgpack, written here from
// docs/protocol.md).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>
#include <zmq.hpp>

#include "net/step_test_client.h"
#include "support/step_server_fixture.h"
#include "support/wait.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"

// A namespace of their own: their plain nlohmann::json alias must not meet net::Json (the
// ordered one) where a unity build puts several test files in one translation unit.
namespace urlab::net::tests {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Json = nlohmann::json;
using urlab::testing::WaitFor;

constexpr const char* kRecorderArmXml = R"(<mujoco model="arm">
  <option timestep="0.002"/>
  <worldbody>
    <body name="link" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.05"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
</mujoco>
)";

using test_client::Client;

class StepServerRecorderTest : public urlab::testing::ServedSessionTest {
 protected:
  void SetUp() override { urlab::testing::WriteTextFile(dir_, "arm.xml", kRecorderArmXml); }
  void Play(bool with_recorder = true) {
    replay::RecorderSubsystem* recorder = nullptr;
    if (with_recorder) {
      recorder = &static_cast<replay::RecorderSubsystem&>(
          manager_.AddSubsystem(std::make_unique<replay::RecorderSubsystem>()));
    }
    NetworkOptions o = urlab::testing::AutoPorts();
    o.files_dir = dir_;  // clients name files in the test's folder
    Serve("control_source: network\narticulations:\n  - {name: arm, mjcf: arm.xml}\n", o,
          [&](NetworkSubsystem& net) { net.SetRecorder(recorder); });
    client_ = std::make_unique<Client>(ctx_, rpc());
    client_->Hello();
  }
  // Drives the arm with a changing torque for `steps` direct-mode steps.
  void Drive(int steps) {
    for (int i = 0; i < steps; ++i) {
      const Json r = client_->Op(
          "step", {{"per_articulation", {{"arm", {{"ctrl", {0.5 * std::sin(0.1 * i)}}}}}}});
      ASSERT_EQ(r["op"], "step_ok") << r.dump();
    }
  }
  Client& c() { return *client_; }

  std::unique_ptr<Client> client_;
};

TEST_F(StepServerRecorderTest, RecordsARunThatReSimulatesBitForBit) {
  Play();
  const std::string path = dir_ + "/run.urrec";
  ASSERT_EQ(c().Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  const Json start = c().Op("recording_start", {{"path", "run.urrec"}});
  ASSERT_EQ(start["op"], "recording_start_ok") << start.dump();
  EXPECT_EQ(start["path"], path);
  const Json again = c().Op("recording_start", {{"path", "other.urrec"}});
  EXPECT_EQ(again["code"], "recording_already_active") << again.dump();
  // The recording starts at the recorder's first keyframe (requested by its writer thread).
  ASSERT_TRUE(WaitFor([&] {
    Drive(1);
    return c().Op("recording_status")["frames"] > 0;
  }));
  Drive(60);
  const Json status = c().Op("recording_status");
  EXPECT_EQ(status["active"], true) << status.dump();
  ASSERT_TRUE(WaitFor([&] { return c().Op("recording_status")["frames"] >= 60; }));
  const Json stop = c().Op("recording_stop");
  ASSERT_EQ(stop["op"], "recording_stop_ok") << stop.dump();
  EXPECT_EQ(stop["path"], path);
  EXPECT_GE(stop["frames"].get<std::uint64_t>(), 60u);
  EXPECT_EQ(stop["dropped"], 0);
  EXPECT_GT(stop["bytes"].get<std::uint64_t>(), 0u);
  // Every recorded frame is one 2 ms step: the duration follows from the frames. (How many
  // steps were driven before the first frame showed in the status depends on the writer
  // thread's scheduling, so it is not a fixed 60.)
  EXPECT_NEAR(stop["duration"].get<double>(),
              static_cast<double>(stop["frames"].get<std::uint64_t>() - 1) * 0.002, 1e-9);
  EXPECT_EQ(c().Op("recording_stop")["code"], "recording_not_active");
  EXPECT_EQ(c().Op("recording_status")["active"], false);

  const replay::RecordingReader reader = replay::RecordingReader::Open(path);
  const replay::ResimReport report = replay::Resimulate(reader);
  EXPECT_TRUE(report.identical) << report.str();
  EXPECT_GE(report.steps_checked, 59u);

  const Json saved = c().Op("recording_save", {{"path", "copy.urrec"}});
  EXPECT_EQ(saved["op"], "recording_save_ok") << saved.dump();
  EXPECT_TRUE(fs::exists(dir_ + "/copy.urrec"));
  EXPECT_EQ(c().Op("recording_clear")["op"], "recording_clear_ok");
}

TEST_F(StepServerRecorderTest, RecorderErrorsHaveTheirCodes) {
  Play();
  EXPECT_EQ(c().Op("recording_stop")["code"], "recording_not_active");
  // A folder where the name must go: not a regular file, refused before anything is opened.
  ASSERT_TRUE(fs::create_directory(dir_ + "/taken.urrec"));
  const Json bad = c().Op("recording_start", {{"path", "taken.urrec"}});
  EXPECT_EQ(bad["code"], "path_not_writable") << bad.dump();
  // A path instead of a name.
  EXPECT_EQ(c().Op("recording_start", {{"path", dir_ + "/run.urrec"}})["code"], "bad_file_name");
  const Json negative = c().Op("recording_start", {{"max_duration", -1}});
  EXPECT_EQ(negative["code"], "bad_value") << negative.dump();
  EXPECT_EQ(c().Op("recording_start", {{"compress", "yes"}})["code"], "bad_value");
  EXPECT_EQ(c().Op("recording_status")["active"], false);
}

// The 2026 client sends the path its user gives: recording_save and replay_load take an
// absolute path directly in the files folder in its sessions; every other path, operation and
// client keeps its refusal.
TEST_F(StepServerRecorderTest, A2026SessionSavesAndLoadsByAnAbsolutePathInTheFilesFolder) {
  Play();  // our session: c()
  Client v2026(ctx_, rpc());
  ASSERT_EQ(v2026.Hello({{"client_version", "urlab_bridge/2026.1.0"}})["op"], "hello_ok");
  ASSERT_EQ(v2026.Op("set_mode", {{"mode", "stepped"}})["op"], "set_mode_ok");
  ASSERT_EQ(v2026.Op("recording_start")["op"], "recording_start_ok");
  ASSERT_TRUE(WaitFor([&] {
    v2026.Op("step", {{"n_steps", 1}});
    return v2026.Op("recording_status")["frames"] > 2;
  }));
  ASSERT_EQ(v2026.Op("recording_stop")["op"], "recording_stop_ok");

  const std::string target = dir_ + "/typed.urrec";
  const Json saved = v2026.Op("recording_save", {{"path", target}});
  ASSERT_EQ(saved["op"], "recording_save_ok") << saved.dump();
  EXPECT_EQ(saved["absolute_path"], target);
  EXPECT_TRUE(fs::is_regular_file(target));
  const Json again = v2026.Op("recording_save", {{"path", dir_ + "/./typed.urrec"}});
  EXPECT_EQ(again["code"], "file_exists") << again.dump();
  const Json loaded = v2026.Op("replay_load", {{"path", target}});
  EXPECT_EQ(loaded["op"], "replay_load_ok") << loaded.dump();

  // Outside the folder, into a subfolder, out through a link, a link at the name: refused.
  const std::string outside = urlab::testing::MakeTempDir("outside");
  EXPECT_EQ(v2026.Op("recording_save", {{"path", outside + "/x.urrec"}})["code"], "bad_file_name");
  EXPECT_EQ(v2026.Op("recording_save", {{"path", dir_ + "/../x.urrec"}})["code"], "bad_file_name");
  fs::create_directory_symlink(outside, dir_ + "/out");
  EXPECT_EQ(v2026.Op("recording_save", {{"path", dir_ + "/out/x.urrec"}})["code"], "bad_file_name");
  fs::create_symlink(outside + "/y.urrec", dir_ + "/link.urrec");
  EXPECT_EQ(v2026.Op("recording_save", {{"path", dir_ + "/link.urrec"}})["code"],
            "path_not_writable");
  EXPECT_EQ(v2026.Op("replay_load", {{"path", outside + "/x.urrec"}})["code"], "bad_file_name");
  EXPECT_TRUE(fs::is_empty(outside));
  // Snapshots take names only, in both vocabularies.
  EXPECT_EQ(v2026.Op("snapshot_save", {{"path", dir_ + "/snap.bin"}})["code"], "bad_file_name");
  // Our vocabulary: names only (replay_load needs the lease, which the 2026 session holds).
  EXPECT_EQ(c().Op("recording_save", {{"path", dir_ + "/ours.urrec"}})["code"], "bad_file_name");
}

TEST_F(StepServerRecorderTest, WithoutARecorderRecordingIsNotReadyButSnapshotsWork) {
  Play(/*with_recorder=*/false);
  const Json r = c().Op("recording_start");
  EXPECT_EQ(r["code"], "not_ready") << r.dump();
  EXPECT_NE(r["message"].get<std::string>().find("recorder"), std::string::npos);
  const Json s = c().Op("snapshot_save", {{"path", "s.urrec"}});
  EXPECT_EQ(s["op"], "snapshot_save_ok") << s.dump();
}

TEST_F(StepServerRecorderTest, SnapshotSaveAndLoadRoundTrip) {
  Play();
  ASSERT_EQ(c().Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  Drive(25);
  const std::string path = dir_ + "/state.urrec";
  const Json saved = c().Op("snapshot_save", {{"path", "state.urrec"}});
  ASSERT_EQ(saved["op"], "snapshot_save_ok") << saved.dump();
  const double t = saved["time"];
  EXPECT_GE(t, 25 * 0.002 - 1e-9);
  const Json before = c().Op("forward");
  Drive(40);
  const Json loaded = c().Op("snapshot_load", {{"path", "state.urrec"}});
  ASSERT_EQ(loaded["op"], "snapshot_load_ok") << loaded.dump();
  EXPECT_EQ(loaded["time"].get<double>(), t);
  const Json after = c().Op("forward");  // the state shown once the restore took effect
  EXPECT_EQ(after["time"].get<double>(), t);
  EXPECT_EQ(after["per_articulation"]["arm"]["qpos"], before["per_articulation"]["arm"]["qpos"]);
  EXPECT_EQ(after["per_articulation"]["arm"]["qvel"], before["per_articulation"]["arm"]["qvel"]);

  EXPECT_EQ(c().Op("snapshot_save", {{"path", "arm.xml/s.urrec"}})["code"], "bad_file_name");
  EXPECT_EQ(c().Op("snapshot_load", {{"path", "missing.urrec"}})["code"], "path_not_readable");
  EXPECT_EQ(c().Op("snapshot_load", {{"path", "arm.xml"}})["code"], "path_not_readable");
  // Other physics options make another model: refused, naming both hashes.
  ASSERT_EQ(c().Op("set_sim_options", {{"options", {{"timestep", 0.001}}}})["op"],
            "set_sim_options_ok");
  const Json other = c().Op("snapshot_load", {{"path", "state.urrec"}});
  EXPECT_EQ(other["code"], "bad_value") << other.dump();
  EXPECT_NE(other["message"].get<std::string>().find("model hash"), std::string::npos)
      << other.dump();
}

// Options changed at run time are part of the recording (its model and hash are taken when it
// starts): the server that made it loads it, and the recording re-simulates with them.
TEST_F(StepServerRecorderTest, ReplayLoadAcceptsARecordingMadeAfterSetSimOptions) {
  Play();
  ASSERT_EQ(c().Op("set_mode", {{"mode", "direct"}})["op"], "set_mode_ok");
  ASSERT_EQ(c().Op("set_sim_options", {{"options", {{"timestep", 0.001}}}})["op"],
            "set_sim_options_ok");
  const std::string path = dir_ + "/options.urrec";  // clients name files under files_dir
  ASSERT_EQ(c().Op("recording_start", {{"path", "options.urrec"}})["op"], "recording_start_ok");
  ASSERT_TRUE(WaitFor([&] {
    Drive(1);
    return c().Op("recording_status")["frames"] > 0;
  }));
  Drive(40);
  ASSERT_TRUE(WaitFor([&] { return c().Op("recording_status")["frames"] >= 40; }));
  ASSERT_EQ(c().Op("recording_stop")["op"], "recording_stop_ok");

  const Json load = c().Op("replay_load", {{"path", "options.urrec"}});
  EXPECT_EQ(load["op"], "replay_load_ok") << load.dump();
  const replay::RecordingReader reader = replay::RecordingReader::Open(path);
  EXPECT_EQ(replay::LoadRecordedModel(reader)->opt.timestep, 0.001);
  const replay::ResimReport report = replay::Resimulate(reader);
  EXPECT_TRUE(report.identical) << report.str();
}

TEST_F(StepServerRecorderTest, ReplaySessionsAndKinematicPlayback) {
  Play();
  const Json missing = c().Op("replay_load", {{"path", "missing.urrec"}});
  EXPECT_EQ(missing["code"], "path_not_readable") << missing.dump();
  EXPECT_NE(missing["message"].get<std::string>().find("missing.urrec"), std::string::npos);
  EXPECT_EQ(c().Op("replay_set_active", {{"session", "r9"}})["code"], "replay_session_not_found");
  EXPECT_EQ(c().Op("replay_start")["code"], "replay_session_not_found");

  // A second of recording in live mode.
  const std::string path = dir_ + "/run.urrec";
  ASSERT_EQ(c().Op("recording_start", {{"path", "run.urrec"}})["op"], "recording_start_ok");
  ASSERT_TRUE(WaitFor([&] { return c().Op("recording_status")["duration"] >= 0.3; }));
  ASSERT_EQ(c().Op("recording_stop")["op"], "recording_stop_ok");

  const Json load = c().Op("replay_load", {{"path", "run.urrec"}});
  ASSERT_EQ(load["op"], "replay_load_ok") << load.dump();
  EXPECT_EQ(load["session"], "r1");
  EXPECT_EQ(load["finished"], true);
  EXPECT_GE(load["duration"].get<double>(), 0.29);
  EXPECT_GT(load["frames"].get<std::uint64_t>(), 100u);
  const Json list = c().Op("replay_list_sessions");
  ASSERT_EQ(list["sessions"].size(), 1u) << list.dump();
  EXPECT_EQ(list["sessions"][0]["session"], "r1");
  EXPECT_EQ(list["sessions"][0]["path"], path);
  EXPECT_EQ(c().Op("replay_set_active", {{"session", "r1"}})["op"], "replay_set_active_ok");
  EXPECT_EQ(c().Op("replay_status")["active"], false);

  EXPECT_EQ(c().Op("replay_start", {{"mode", "backwards"}})["code"], "bad_value");
  const Json start = c().Op("replay_start", {{"mode", "kinematic"}});
  ASSERT_EQ(start["op"], "replay_start_ok") << start.dump();
  EXPECT_EQ(start["session"], "r1");
  double first = -1;
  ASSERT_TRUE(WaitFor([&] {
    const Json st = c().Op("replay_status");
    if (first < 0) first = st["time"];
    return st["time"].get<double>() > first + 0.05;
  })) << c().Op("replay_status").dump();
  const Json st = c().Op("replay_status");
  EXPECT_EQ(st["mode"], "kinematic");
  EXPECT_TRUE(st["error"].get<std::string>().empty()) << st.dump();
  EXPECT_EQ(c().Op("replay_stop")["op"], "replay_stop_ok");
  EXPECT_EQ(c().Op("replay_status")["active"], false);

  // Puppet mode never steps: no replay there.
  ASSERT_EQ(c().Op("set_mode", {{"mode", "puppet"}})["op"], "set_mode_ok");
  EXPECT_EQ(c().Op("replay_start")["code"], "replay_requires_stepped");
}

}  // namespace
}  // namespace urlab::net::tests
