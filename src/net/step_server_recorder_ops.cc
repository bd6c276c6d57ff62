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
#include "urlab/world/batch_subsystem.h"

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
  // The 2026 client sends the path its user gives, usually absolute: one in the files folder is
  // the name there (NetworkFiles::NameOf); WritablePath then judges it as any name.
  if (const auto it = r.body.find("path"); r.v2026 && it != r.body.end() && it->is_string()) {
    *it = files_.NameOf(it->get<std::string>(), "path");
  }
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

// ---- Replay: the wire's fields to ops::ReplaySessions and its results to replies.

StepServer::Outcome StepServer::ReplayLoad(Request& r) {
  std::string name = String(r.body["path"], "path");
  // The 2026 client sends the path its user gives (often recording_save's absolute_path): one
  // in the files folder is the name there; any other stays refused.
  if (r.v2026) name = files_.NameOf(name, "path");
  const std::string path = files_.ForReading(name, "path");
  std::string id;
  const replay::RecordingReader* rd = nullptr;
  RunFileOp([&] { rd = &replays_.Load(r.client->id, path, &id); }, "path_not_readable");
  return {Json{{"op", "replay_load_ok"},
               {"session", id},
               {"path", rd->path()},
               {"frames", rd->frame_count()},
               {"duration", rd->frame_count() > 0 ? rd->last_time() - rd->first_time() : 0.0},
               {"chunks", rd->chunks().size()},
               {"finished", rd->finished()},
               {"problem", rd->problem()}}};
}

StepServer::Outcome StepServer::ReplayListSessions(Request&) {
  Json sessions = Json::array();
  for (const ops::ReplaySessions::Entry& s : replays_.List()) {
    sessions.push_back(
        Json{{"session", s.id}, {"path", s.path}, {"frames", s.frames}, {"active", s.active}});
  }
  const std::string& active = replays_.active();
  return {Json{{"op", "replay_list_sessions_ok"},
               {"sessions", std::move(sessions)},
               {"active", active.empty() ? Json() : Json(active)}}};
}

StepServer::Outcome StepServer::ReplaySetActive(Request& r) {
  const std::string id = String(r.body["session"], "session");
  replays_.SetActive(id);
  return {Json{{"op", "replay_set_active_ok"}, {"session", id}}};
}

StepServer::Outcome StepServer::ReplayStart(Request& r) {
  if (batch_ && batch_->envs() > 1) {
    Fail("bad_mode", "replay_start: this run steps " + std::to_string(batch_->envs()) +
                         " environments together (urlab run --envs), and a replay would move "
                         "one of them alone; replay the recording in a run without --envs "
                         "(urlab replay FILE, or urlab run SCENE and replay_start)");
  }
  ops::ReplaySessions::StartRequest o;
  if (const auto it = r.body.find("session"); it != r.body.end() && !it->is_null()) {
    o.session = String(*it, "session");
  }
  if (r.body.contains("mode")) o.mode = String(r.body["mode"], "mode");
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
  const ops::ReplaySessions::Started s = replays_.Start(o);
  LogRemote(spdlog::level::info, "replay start",
            fmt::format("step server: replaying {} ({}, speed {})", s.path, s.mode, s.speed));
  return {Json{{"op", "replay_start_ok"},
               {"session", s.id},
               {"mode", s.mode},
               {"speed", s.speed},
               {"loop", s.loop},
               {"frames", s.frames}}};
}

StepServer::Outcome StepServer::ReplayStop(Request&) {
  const std::string was = replays_.Stop();  // the engine steps on its own again
  return {Json{{"op", "replay_stop_ok"}, {"session", was.empty() ? Json() : Json(was)}}};
}

StepServer::Outcome StepServer::ReplayStatus(Request&) {
  const ops::ReplaySessions::Status st = replays_.GetStatus();
  if (!st.active) return {Json{{"op", "replay_status_ok"}, {"active", false}}};
  const replay::PlayerStatus& p = st.player;
  Json resim{{"identical", p.resim.identical},
             {"steps_checked", p.resim.steps_checked},
             {"diverged", p.resim.diverged}};
  if (p.resim.diverged) resim["report"] = p.resim.str();
  return {Json{{"op", "replay_status_ok"},
               {"active", true},
               {"session", st.session},
               {"mode", st.mode},
               {"playing", p.playing},
               {"finished", p.finished},
               {"time", p.time},
               {"step", p.step},
               {"frame", p.frame},
               {"frames", p.frames},
               {"speed", p.speed},
               {"loop", p.loop},
               {"loops", p.loops},
               {"resim", std::move(resim)},
               {"error", p.error}}};
}

StepServer::Outcome StepServer::ReplayUnload(Request& r) {
  std::string id;
  if (const auto it = r.body.find("session"); it != r.body.end() && !it->is_null()) {
    id = String(*it, "session");
  }
  return {Json{{"op", "replay_unload_ok"}, {"session", replays_.Unload(id)}}};
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
