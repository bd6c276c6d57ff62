// The step server's recorder operations (docs/protocol.md, "Runtime operations"): recordings
// through the recorder subsystem the network was given, snapshots of the engine's state, and replay
// of loaded recordings through a Player on the live engine. File operations block the I/O thread
// for their duration; leases run from their end.
#include <mujoco/mujoco.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "net/request_fields.h"
#include "net/step_server.h"
#include "net/value_ranges.h"
#include "urlab/ops/error.h"
#include "urlab/ops/recording.h"
#include "urlab/physics/model.h"

namespace urlab::net {

using namespace request;

namespace {

using Reason = replay::RecordingError::Reason;

double OptionalNumber(const Json& body, const char* field, double fallback) {
  const auto it = body.find(field);
  return it == body.end() || it->is_null() ? fallback : Number(*it, field);
}

bool OptionalBool(const Json& body, const char* field, bool fallback) {
  const auto it = body.find(field);
  return it == body.end() || it->is_null() ? fallback : Bool(*it, field);
}

StepServer::Json StatusJson(const replay::RecorderStatus& s) {
  return StepServer::Json{{"active", s.active},     {"path", s.path},
                          {"frames", s.frames},     {"chunks", s.chunks},
                          {"bytes", s.bytes},       {"raw_bytes", s.raw_bytes},
                          {"dropped", s.dropped},   {"markers", s.markers},
                          {"duration", s.duration}, {"stopped_because", s.stopped_because}};
}

}  // namespace

replay::Recorder& StepServer::RequireRecorder() { return ops::RequireRecorder(recorder_); }

void StepServer::RefreshLeases() {
  const auto now = Clock::now();
  for (auto& [id, client] : clients_) client.last_seen = std::max(client.last_seen, now);
}

void StepServer::RunFileOp(const std::function<void()>& op, const char* other_errors) {
  try {
    op();
  } catch (const ops::OpError&) {  // the operations' own refusals, as they are
    RefreshLeases();
    throw;
  } catch (const replay::RecorderError& e) {
    RefreshLeases();
    Fail(e.code(), e.what());
  } catch (const replay::RecordingError& e) {
    RefreshLeases();
    Fail(e.reason() == Reason::kWrongModel ? "bad_value" : "path_not_readable", e.what());
  } catch (const std::exception& e) {
    if (!other_errors) throw;
    RefreshLeases();
    Fail(other_errors, e.what());
  }
  RefreshLeases();
}

// ---- Recordings

StepServer::Outcome StepServer::RecordingStart(Request& r) {
  // A name in the files folder (a fresh one when none is given); the recorder writes NAME.part
  // and renames it to NAME at the end: neither may be anything but a regular file, and NAME is
  // not replaced unless the request says overwrite.
  std::string name;
  if (const auto it = r.body.find("path"); it != r.body.end() && !it->is_null()) {
    name = String(*it, "path");
  } else {
    name = files_.FreshName("recording", ".urrec");
  }
  ops::RequireIdleRecorder(recorder_);  // before the file checks
  ops::RecordingRequest o;
  o.path = files_.ForWriting(name, "path", OptionalBool(r.body, "overwrite", false), {kPartSuffix});
  o.compress = OptionalBool(r.body, "compress", true);
  o.sensordata = OptionalBool(r.body, "sensordata", false);
  o.keyframe_interval = OptionalNumber(r.body, "keyframe_interval", o.keyframe_interval);
  o.max_duration = OptionalNumber(r.body, "max_duration", o.max_duration);
  o.ring_seconds = OptionalNumber(r.body, "ring_seconds", o.ring_seconds);
  std::string path;
  RunFileOp([&] { path = ops::StartRecording(recorder_, o); });
  return {Json{{"op", "recording_start_ok"}, {"path", path}, {"max_duration", o.max_duration}}};
}

StepServer::Outcome StepServer::RecordingStop(Request&) {
  replay::RecorderStatus s;
  RunFileOp([&] { s = ops::StopRecording(recorder_); });
  return {Json{{"op", "recording_stop_ok"},
               {"path", s.path},
               {"frames", s.frames},
               {"duration", s.duration},
               {"bytes", s.bytes},
               {"dropped", s.dropped}}};
}

StepServer::Outcome StepServer::RecordingSave(Request& r) {
  RequireRecorder();
  const std::string path = WritablePath(r);
  std::string saved;
  RunFileOp([&] { saved = ops::SaveRecording(recorder_, path); });
  // absolute_path: where the file is on this host (the 2026 client reads it).
  std::error_code ec;
  const std::filesystem::path where = std::filesystem::absolute(saved, ec);
  return {Json{{"op", "recording_save_ok"},
               {"path", saved},
               {"absolute_path", ec ? saved : where.lexically_normal().string()}}};
}

StepServer::Outcome StepServer::RecordingClear(Request&) {
  ops::ClearRecording(recorder_);
  return {Json{{"op", "recording_clear_ok"}}};
}

StepServer::Outcome StepServer::RecordingStatus(Request&) {
  Json reply = StatusJson(ops::RecordingStatus(recorder_));
  reply["op"] = "recording_status_ok";
  return {reply};
}

// ---- Snapshots

StepServer::Outcome StepServer::SnapshotSave(Request& r) {
  const std::string path = WritablePath(r);
  double time = 0;
  RunFileOp([&] { time = ops::SaveSnapshot(session_, recorder_, path); });
  return {Json{{"op", "snapshot_save_ok"}, {"path", path}, {"time", time}}};
}

StepServer::Outcome StepServer::SnapshotLoad(Request& r) {
  const std::string path = files_.ForReading(String(r.body["path"], "path"), "path");
  ops::Restored restored;
  RunFileOp([&] { restored = ops::LoadSnapshot(session_, path); });
  Outcome out;
  out.reply = Json{{"op", "snapshot_load_ok"}, {"path", path}, {"time", restored.time}};
  out.wait_for = restored.seq;
  return out;
}

// ---- Replay

StepServer::Outcome StepServer::ReplayLoad(Request& r) {
  std::string name = String(r.body["path"], "path");
  if (r.v2026) {
    // The 2026 client names a file by the absolute_path recording_save answered: one inside
    // the files folder is the name under it (any other stays refused as a path).
    std::error_code ec;
    const std::filesystem::path dir =
        std::filesystem::absolute(files_.dir(), ec).lexically_normal();
    const std::filesystem::path given(name);
    if (!ec && given.is_absolute()) {
      const std::filesystem::path rel = given.lexically_normal().lexically_relative(dir);
      if (!rel.empty() && *rel.begin() != "..") name = rel.string();
    }
  }
  const std::string path = files_.ForReading(name, "path");
  // A new load releases this client's earlier recordings (except one playing); the total is
  // bounded too.
  ReleaseReplays(r.client->id, playing_replay_);
  if (replays_.size() >= options_.limits.max_replay_sessions) {
    Fail("replay_limit", std::to_string(replays_.size()) +
                             " recordings are loaded (the limit); replay_unload one first");
  }
  std::unique_ptr<replay::RecordingReader> reader;
  RunFileOp(
      [&] {
        reader = std::make_unique<replay::RecordingReader>(
            replay::RecordingReader::Open(path, {.allow_partial = true}));
        replay::CheckSameModel(*reader, session_.engine().CopyModel());
      },
      "path_not_readable");
  if (reader->info().kind != "recording") {
    Fail("path_not_readable", path + ": not a recording (a " + reader->info().kind + ")");
  }
  // fmt, not "r" + std::to_string: GCC 12 -O3 raises a false -Wrestrict on the latter.
  ReplaySession s{fmt::format("r{}", next_replay_++), r.client->id, std::move(reader)};
  const replay::RecordingReader& rd = *s.reader;
  Json reply{{"op", "replay_load_ok"},
             {"session", s.id},
             {"path", rd.path()},
             {"frames", rd.frame_count()},
             {"duration", rd.frame_count() > 0 ? rd.last_time() - rd.first_time() : 0.0},
             {"chunks", rd.chunks().size()},
             {"finished", rd.finished()},
             {"problem", rd.problem()}};
  active_replay_ = s.id;  // the newest recording is the one replay_start plays by default
  replays_.push_back(std::move(s));
  return {reply};
}

StepServer::Outcome StepServer::ReplayListSessions(Request&) {
  Json sessions = Json::array();
  for (const ReplaySession& s : replays_) {
    sessions.push_back(Json{{"session", s.id},
                            {"path", s.reader->path()},
                            {"frames", s.reader->frame_count()},
                            {"active", s.id == active_replay_}});
  }
  return {Json{{"op", "replay_list_sessions_ok"},
               {"sessions", std::move(sessions)},
               {"active", active_replay_.empty() ? Json() : Json(active_replay_)}}};
}

StepServer::Outcome StepServer::ReplaySetActive(Request& r) {
  const std::string id = String(r.body["session"], "session");
  if (std::none_of(replays_.begin(), replays_.end(),
                   [&id](const ReplaySession& s) { return s.id == id; })) {
    Fail("replay_session_not_found", "no replay session '" + id + "' (see replay_list_sessions)");
  }
  active_replay_ = id;
  return {Json{{"op", "replay_set_active_ok"}, {"session", id}}};
}

StepServer::Outcome StepServer::ReplayStart(Request& r) {
  std::string id = active_replay_;
  if (const auto it = r.body.find("session"); it != r.body.end() && !it->is_null()) {
    id = String(*it, "session");
  }
  const auto s = std::find_if(replays_.begin(), replays_.end(),
                              [&id](const ReplaySession& x) { return x.id == id; });
  if (s == replays_.end()) {
    Fail("replay_session_not_found",
         id.empty() ? std::string("no recording loaded (replay_load first)")
                    : "no replay session '" + id + "' (see replay_list_sessions)");
  }
  replay::PlayerOptions o;
  const std::string mode =
      r.body.contains("mode") ? String(r.body["mode"], "mode") : std::string("kinematic");
  if (mode == "kinematic") {
    o.mode = replay::PlayMode::kKinematic;
  } else if (mode == "resimulate") {
    o.mode = replay::PlayMode::kResimulate;
  } else {
    Fail("bad_value", "mode must be kinematic or resimulate");
  }
  o.speed = 1.0;
  if (const auto it = r.body.find("speed"); it != r.body.end() && !it->is_null()) {
    o.speed = RangedNumber(*it, "speed");
  }
  o.loop = OptionalBool(r.body, "loop", false);
  // The player runs in the engine's step handler: puppet mode never steps the engine.
  if (mode_ == "puppet") {
    Fail("replay_requires_stepped",
         "replay plays through physics steps; puppet mode never steps (set_mode live or "
         "direct)");
  }
  if (playback_) playback_->Set(nullptr);  // the viewer's timeline lets go of the old player
  shown_.reset();
  player_.reset();  // one replay at a time: a new start replaces it
  try {
    player_ = std::make_unique<replay::Player>(session_.engine(), *s->reader, o);
  } catch (const replay::RecordingError& e) {
    Fail(e.reason() == Reason::kWrongModel ? "bad_value" : "path_not_readable", e.what());
  }
  playing_replay_ = id;
  player_mode_ = mode;
  if (playback_) {  // a running viewer shows it on its timeline
    auto shown = std::make_unique<replay::Playback>();
    shown->player = player_.get();
    shown->reader = s->reader.get();
    try {
      shown->marks = replay::ScanTimeline(*s->reader);
    } catch (const replay::RecordingError& e) {
      spdlog::warn("step server: the timeline shows no keyframes or resets: {}", e.what());
    }
    shown->label = id + ": " + s->reader->path();
    shown->mode = mode;
    shown_ = std::move(shown);
    playback_->Set(shown_.get());
  }
  LogRemote(
      spdlog::level::info, "replay start",
      fmt::format("step server: replaying {} ({}, speed {})", s->reader->path(), mode, o.speed));
  return {Json{{"op", "replay_start_ok"},
               {"session", id},
               {"mode", mode},
               {"speed", o.speed},
               {"loop", o.loop},
               {"frames", s->reader->frame_count()}}};
}

StepServer::Outcome StepServer::ReplayStop(Request&) {
  const std::string was = player_ ? playing_replay_ : std::string();
  if (playback_) playback_->Set(nullptr);
  shown_.reset();
  player_.reset();  // the engine steps on its own again
  playing_replay_.clear();
  return {Json{{"op", "replay_stop_ok"}, {"session", was.empty() ? Json() : Json(was)}}};
}

StepServer::Outcome StepServer::ReplayStatus(Request&) {
  if (!player_) return {Json{{"op", "replay_status_ok"}, {"active", false}}};
  const replay::PlayerStatus st = player_->status();
  Json resim{{"identical", st.resim.identical},
             {"steps_checked", st.resim.steps_checked},
             {"diverged", st.resim.diverged}};
  if (st.resim.diverged) resim["report"] = st.resim.str();
  return {Json{{"op", "replay_status_ok"},
               {"active", true},
               {"session", playing_replay_},
               {"mode", player_mode_},
               {"playing", st.playing},
               {"finished", st.finished},
               {"time", st.time},
               {"step", st.step},
               {"frame", st.frame},
               {"frames", st.frames},
               {"speed", st.speed},
               {"loop", st.loop},
               {"loops", st.loops},
               {"resim", std::move(resim)},
               {"error", st.error}}};
}

StepServer::Outcome StepServer::ReplayUnload(Request& r) {
  std::string id = active_replay_;
  if (const auto it = r.body.find("session"); it != r.body.end() && !it->is_null()) {
    id = String(*it, "session");
  }
  if (ReleaseReplaysIf([&id](const ReplaySession& s) { return s.id == id; }) == 0) {
    Fail("replay_session_not_found",
         id.empty() ? std::string("no recording loaded")
                    : "no replay session '" + id + "' (see replay_list_sessions)");
  }
  return {Json{{"op", "replay_unload_ok"}, {"session", id}}};
}

std::size_t StepServer::ReleaseReplays(const std::string& owner, const std::string& keep) {
  return ReleaseReplaysIf([&](const ReplaySession& s) {
    return (owner.empty() || s.owner == owner) && (keep.empty() || s.id != keep);
  });
}

std::size_t StepServer::ReleaseReplaysIf(const std::function<bool(const ReplaySession&)>& which) {
  std::size_t n = 0;
  for (auto it = replays_.begin(); it != replays_.end();) {
    if (!which(*it)) {
      ++it;
      continue;
    }
    if (it->id == playing_replay_) {
      if (playback_) playback_->Set(nullptr);  // the viewer's timeline lets go first
      shown_.reset();
      player_.reset();  // the reader it plays goes away: the engine steps on its own again
      playing_replay_.clear();
    }
    if (it->id == active_replay_) active_replay_.clear();
    it = replays_.erase(it);
    ++n;
  }
  if (active_replay_.empty() && !replays_.empty()) active_replay_ = replays_.back().id;
  return n;
}

std::string StepServer::WritablePath(const Request& r) {
  const std::string name = String(r.body.at("path"), "path");
  const std::string path =
      files_.ForWriting(name, "path", OptionalBool(r.body, "overwrite", false), {kPartSuffix});
  // Nor the file a running recording is making.
  replay::Recorder* recorder = recorder_ ? recorder_->recorder() : nullptr;
  if (recorder && recorder->active()) {
    const std::string& active = recorder->status().path;
    if (path == active) {
      Fail("file_exists", "'" + name + "' is the file the running recording writes");
    }
  }
  return path;
}

}  // namespace urlab::net
