// Recording and snapshots (urlab/ops/recording.h): the step server's recording_* and
// snapshot_* and the viewer panel's Record / Stop recording / Snapshot / Restore are the same
// operations, with the same refusals. Replay sessions (urlab/ops/replay_sessions.h) are a module of
// their own the step server's replay_* operations route to.
#include "urlab/ops/recording.h"

#include <filesystem>

#include "ops/ops_fixture.h"
#include "urlab/ops/replay_sessions.h"

namespace urlab::ops::test {
namespace {

TEST_F(OpsTest, RecordingRefusesAlikeOnEveryPath) {
  Play("direct", "", "", /*recorder=*/true);
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("recording_start", {{"path", "one.urrec"}})["op"], "recording_start_ok");
  EXPECT_EQ(FromReply(c.Op("recording_start", {{"path", "two.urrec"}})),
            FromCall([&] { StartRecording(recorder_, {.path = dir_ + "/two.urrec"}); }));
  EXPECT_EQ(FromCall([&] { StartRecording(recorder_, {.path = dir_ + "/two.urrec"}); }).code,
            "recording_already_active");
  EXPECT_TRUE(RecordingStatus(recorder_).active);
  c.Op("step", {{"n_steps", 5}});
  const replay::RecorderStatus st = StopRecording(recorder_);  // the panel's Stop recording
  EXPECT_EQ(st.frames, 5u);
  EXPECT_TRUE(std::filesystem::exists(dir_ + "/one.urrec"));
  EXPECT_FALSE(c.Op("recording_status")["active"].get<bool>());
  // Started from the panel's path, stopped from the wire.
  EXPECT_EQ(StartRecording(recorder_, {.path = dir_ + "/three.urrec"}), dir_ + "/three.urrec");
  c.Op("step", {{"n_steps", 2}});
  EXPECT_EQ(c.Op("recording_stop")["frames"], 2);
}

TEST_F(OpsTest, WithoutARecorderEveryPathSaysNotReady) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  EXPECT_EQ(FromReply(c.Op("recording_status")), FromCall([&] { RecordingStatus(nullptr); }));
  EXPECT_EQ(FromReply(c.Op("recording_stop")), FromCall([&] { StopRecording(nullptr); }));
  EXPECT_EQ(FromCall([&] { StartRecording(nullptr, {.path = dir_ + "/x.urrec"}); }).code,
            "not_ready");
}

TEST_F(OpsTest, SnapshotsRoundTripAcrossPaths) {
  Play("direct");
  Client c(ctx_, rpc());
  c.Hello();
  c.Op("step", {{"n_steps", 7}});
  const double t = SaveSnapshot(session(), nullptr, dir_ + "/s.snap");
  EXPECT_NEAR(t, 0.014, 1e-12);
  c.Op("step", {{"n_steps", 3}});
  const Json r = c.Op("snapshot_load", {{"path", "s.snap"}});
  ASSERT_EQ(r["op"], "snapshot_load_ok") << r.dump();
  EXPECT_EQ(r["time"], t);
  EXPECT_EQ(c.Op("forward")["time"], t);
  EXPECT_EQ(FromCall([&] { LoadSnapshot(session(), dir_ + "/missing.snap"); }).code,
            "path_not_readable");
  // In memory (the panel's Snapshot / Restore).
  const physics::PhysicsState state = TakeState(session());
  c.Op("step", {{"n_steps", 3}});
  Wait(RestoreState(session(), state));
  EXPECT_EQ(c.Op("forward")["time"], t);
  physics::PhysicsState wrong = state;
  wrong.qpos.resize(1);
  EXPECT_EQ(FromCall([&] { RestoreState(session(), wrong); }).code, "bad_value");
}

TEST_F(OpsTest, ReplaySessionsPlayWithoutTheStepServer) {
  Play("direct", "", "", /*recorder=*/true);
  Client c(ctx_, rpc());
  c.Hello();
  ASSERT_EQ(c.Op("recording_start", {{"path", "run.urrec"}})["op"], "recording_start_ok");
  c.Op("step", {{"n_steps", 50}});
  ASSERT_EQ(c.Op("recording_stop")["frames"], 50);
  const std::string file = dir_ + "/run.urrec";

  // The module alone (the step server holds another instance): the same refusals.
  ReplaySessions replays(session(), /*max_sessions=*/2);
  EXPECT_EQ(FromReply(c.Op("replay_start")), FromCall([&] { replays.Start({}); }));
  EXPECT_EQ(FromCall([&] { replays.Start({}); }).code, "replay_session_not_found");
  std::string a, b;
  EXPECT_EQ(replays.Load("panel", file, &a).frame_count(), 50u);
  EXPECT_EQ(a, "r1");
  replays.Load("panel", file, &b);  // the owner's earlier one is released
  EXPECT_EQ(b, "r2");
  ASSERT_EQ(replays.List().size(), 1u);
  EXPECT_TRUE(replays.List()[0].active);
  ASSERT_EQ(c.Op("replay_load", {{"path", "run.urrec"}})["op"], "replay_load_ok");
  EXPECT_EQ(FromReply(c.Op("replay_set_active", {{"session", "r9"}})),
            FromCall([&] { replays.SetActive("r9"); }));
  EXPECT_EQ(FromReply(c.Op("replay_start", {{"mode", "fast"}})),
            FromCall([&] { replays.Start({.mode = "fast"}); }));
  replays.Load("other", file, &a);
  EXPECT_EQ(FromCall([&] { replays.Load("third", file, &a); }).code, "replay_limit");

  // Plays in the engine's step handler: the engine's steps show the recorded frames.
  const ReplaySessions::Started started = replays.Start({.session = b});
  EXPECT_EQ(started.frames, 50u);
  c.Op("step", {{"n_steps", 10}});
  const ReplaySessions::Status st = replays.GetStatus();
  EXPECT_TRUE(st.active);
  EXPECT_EQ(st.session, b);
  EXPECT_GT(st.player.frame, 0u);
  // Releasing the playing one stops it; the other stays, active.
  EXPECT_EQ(replays.Release("panel"), 1u);
  EXPECT_FALSE(replays.GetStatus().active);
  EXPECT_EQ(replays.active(), "r3");
  EXPECT_EQ(replays.Unload(""), "r3");
  EXPECT_TRUE(replays.List().empty());
}

}  // namespace
}  // namespace urlab::ops::test
