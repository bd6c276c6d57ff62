#include "net/step_server.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>
#include <random>
#include <zmq_addon.hpp>

#include "net/base64.h"
#include "net/camera_list.h"
#include "net/dialect_2026.h"
#include "net/dialect_2026_hello.h"
#include "net/loopback.h"
#include "net/model_assets.h"
#include "net/observation.h"
#include "net/port_owner.h"
#include "net/request_fields.h"
#include "net/value_ranges.h"
#include "urlab/control/controller.h"
#include "urlab/core/version.h"
#include "urlab/ops/controllers.h"
#include "urlab/ops/simulation.h"
#include "urlab/ops/state.h"
#include "urlab/ops/targets.h"
#include "urlab/replay/tables.h"
#include "urlab/world/batch_subsystem.h"
#include "urlab/world/names.h"
#include "wire/request_limits.h"

namespace urlab::net {

using namespace request;

namespace {

// How long a reply waits for a camera frame of its own step ("sync").
constexpr auto kCameraSyncTimeout = std::chrono::milliseconds(2000);

std::string NewSessionId(std::uint64_t n) {
  static std::mt19937_64 rng{std::random_device{}()};
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%016llx%04llx", static_cast<unsigned long long>(rng()),
                static_cast<unsigned long long>(n & 0xffff));
  return buf;
}

// `values` written at `adrs` (one address per value) as runs of consecutive addresses.
std::vector<physics::cmd::SetState::Run> Runs(const std::vector<int>& adrs,
                                              const std::vector<double>& values) {
  std::vector<physics::cmd::SetState::Run> runs;
  for (std::size_t i = 0; i < adrs.size(); ++i) {
    if (runs.empty() || adrs[i] != runs.back().adr + static_cast<int>(runs.back().values.size())) {
      runs.push_back({adrs[i], {}});
    }
    runs.back().values.push_back(values[i]);
  }
  return runs;
}

// A request from this host: the server listens on loopback or ipc only, or the peer's address is
// a loopback one.
bool IsLocalPeer(const std::string& endpoint, const zmq::message_t& payload) {
  if (IsLoopbackEndpoint(endpoint)) return true;
  const char* peer = zmq_msg_gets(payload.handle(), "Peer-Address");
  if (!peer) return false;
  const std::string_view a = peer;
  return a.starts_with("127.") || a == "::1" || a.starts_with("::ffff:127.");
}

void Append(std::vector<physics::cmd::SetState::Run>* to,
            std::vector<physics::cmd::SetState::Run> runs) {
  for (auto& run : runs) to->push_back(std::move(run));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The operation catalogue (meta reports it; Dispatch enforces sessions, leases and fields).

const std::vector<StepServer::OpSpec>& StepServer::Ops() {
  static const std::vector<OpSpec> ops = {
      {"hello", &StepServer::Hello, false, false, {}, "session_id, protocol_version, ..."},
      {"meta", &StepServer::Meta, false, false, {}, "operations"},
      {"bye", &StepServer::Bye, true, false, {}, ""},
      {"step", &StepServer::Step, true, true, {}, "time, step, sim_time, per_articulation"},
      {"reset", &StepServer::Reset, true, true, {}, "like step_ok"},
      {"forward", &StepServer::Forward, true, false, {}, "like step_ok"},
      {"set_mode", &StepServer::SetMode, true, true, {"mode"}, "previous_mode, current_mode"},
      {"set_paused", &StepServer::SetPaused, true, true, {"paused"}, "paused"},
      {"set_sim_speed", &StepServer::SetSimSpeed, true, true, {"percent"}, "percent"},
      {"set_control_source",
       &StepServer::SetControlSource,
       true,
       true,
       {"source"},
       "source, articulation"},
      {"set_qpos", &StepServer::SetQpos, true, true, {"articulation", "qpos"}, "like step_ok"},
      {"set_mocap_pose", &StepServer::SetMocapPose, true, true, {"body"}, "body, pos, quat"},
      {"read_mocap_pose", &StepServer::ReadMocapPose, true, false, {"body"}, "body, pos, quat"},
      {"list_keyframes", &StepServer::ListKeyframes, true, false, {}, "keyframes"},
      {"get_contacts",
       &StepServer::GetContacts,
       true,
       false,
       {},
       "contacts, count, matched, truncated, time"},
      {"set_sim_options", &StepServer::SetSimOptions, true, true, {"options"}, "options"},
      {"get_counters", &StepServer::GetCounters, true, false, {}, "errors, clients, driver"},
      {"set_twist",
       &StepServer::SetTwist,
       true,
       true,
       {"articulation"},
       "articulation, linear, angular"},
      {"fire_launcher",
       &StepServer::FireLauncher,
       true,
       true,
       {"launcher"},
       "launcher, projectile"},
      {"configure_controller",
       &StepServer::ConfigureController,
       true,
       true,
       {"articulation", "params"},
       "articulation, kind, params"},
      {"recording_start", &StepServer::RecordingStart, true, true, {}, "path"},
      {"recording_stop",
       &StepServer::RecordingStop,
       true,
       true,
       {},
       "path, frames, duration, bytes, dropped"},
      {"recording_save", &StepServer::RecordingSave, true, false, {"path"}, "path", true},
      {"recording_clear", &StepServer::RecordingClear, true, true, {}, ""},
      {"recording_status",
       &StepServer::RecordingStatus,
       true,
       false,
       {},
       "active, path, frames, chunks, bytes, raw_bytes, dropped, markers, duration, "
       "stopped_because"},
      {"snapshot_save", &StepServer::SnapshotSave, true, false, {"path"}, "path, time", true},
      {"snapshot_load", &StepServer::SnapshotLoad, true, true, {"path"}, "path, time"},
      {"replay_load",
       &StepServer::ReplayLoad,
       true,
       true,
       {"path"},
       "session, path, frames, duration, chunks, finished, problem"},
      {"replay_list_sessions",
       &StepServer::ReplayListSessions,
       true,
       false,
       {},
       "sessions, active"},
      {"replay_set_active", &StepServer::ReplaySetActive, true, true, {"session"}, "session"},
      {"replay_start",
       &StepServer::ReplayStart,
       true,
       true,
       {},
       "session, mode, speed, loop, frames"},
      {"replay_stop", &StepServer::ReplayStop, true, true, {}, "session"},
      {"replay_unload", &StepServer::ReplayUnload, true, true, {}, "session"},
      {"cancel", &StepServer::Cancel, true, true, {}, "cancelled"},
      {"set_camera_streaming", &StepServer::SetCameraStreaming, true, false, {}, "streaming"},
      {"set_latency",
       &StepServer::SetLatency,
       true,
       true,
       {"articulation"},
       "articulation, seed, control, observation"},
      {"get_latency",
       &StepServer::GetLatency,
       true,
       false,
       {"articulation"},
       "articulation, seed, control, observation"},
      {"set_camera_delay", &StepServer::SetCameraDelay, true, true, {}, "cameras"},

      {"replay_status",
       &StepServer::ReplayStatus,
       true,
       false,
       {},
       "active, session, mode, playing, finished, time, step, frame, frames, ..."},
      // Batched environments (step_server_batch_ops.cc).
      {"batch_info",
       &StepServer::BatchInfo,
       true,
       false,
       {},
       "envs, threads, nu, obs_size, obs_layout, action_low, action_high, ..."},
      {"batch_step",
       &StepServer::BatchStep,
       true,
       true,
       {"actions"},
       "obs, done, reset, time, episode_steps, step_seconds"},
      {"batch_reset",
       &StepServer::BatchReset,
       true,
       true,
       {},
       "obs, done, reset, time, episode_steps"},
  };
  return ops;
}

StepServer::StepServer(world::Session& session, const std::vector<ArticulationTopics>& tables,
                       std::shared_ptr<physics::StateSubscription> state, StepServerOptions options)
    : session_(session),
      tables_(tables),
      free_bodies_(FindFreeBodies(session, tables)),
      state_(std::move(state)),
      options_(std::move(options)),
      mode_(options_.mode == "direct" ? "direct" : "live"),
      files_(options_.files_dir, options_.inputs),
      replays_(session, options_.limits.max_replay_sessions) {
  // The compiled model for hello, saved once here (main thread, before the physics thread).
  const mjModel* m = session_.engine().model();
  mjb_.resize(static_cast<std::size_t>(mj_sizeModel(m)));
  mj_saveModel(m, nullptr, mjb_.data(), static_cast<int>(mjb_.size()));
  if (mode_ == "direct") ops::SetPaused(session_, true);
}

std::string StepServer::Bind(zmq::context_t& context, std::string* failure) {
  zmq::socket_t s(context, zmq::socket_type::router);
  s.set(zmq::sockopt::linger, 0);
  s.set(zmq::sockopt::router_mandatory, 0);
  try {
    s.bind(options_.endpoint);
  } catch (const zmq::error_t& e) {
    const std::string why =
        DescribeBindFailure("step server", options_.endpoint, e.num(), e.what());
    if (failure) {
      *failure = why;
    } else {
      spdlog::error("step server: {}; running without it", why);
    }
    return "";
  }
  std::string bound = s.get(zmq::sockopt::last_endpoint);
  if (!IsLoopbackEndpoint(options_.endpoint)) {
    spdlog::warn(
        "step server: {} accepts requests from other hosts (anyone who can reach it may drive "
        "the simulation and write under {}); bind 127.0.0.1 to keep it local",
        options_.endpoint, files_.dir());
  }
  socket_ = std::move(s);
  if (options_.shared_memory) {
    try {
      shm_ = std::make_unique<ShmTransport>(options_.shm);
    } catch (const std::exception& e) {
      spdlog::warn("step server: no shared-memory channels ({}); clients use ZeroMQ", e.what());
    }
  }
  return bound;
}

void StepServer::Close() {
  for (Pending& p : pending_) {
    SendError(p.envelope, p.seq, p.json, "shutting_down", "the simulation is stopping");
  }
  pending_.clear();
  socket_.reset();
  shm_.reset();     // clients waiting on a channel see it closed; the files are removed
  replays_.Stop();  // removes the custom step handler while the engine still runs
  for (const auto& [example, n] : log_limiter_.TakeSkipped()) {
    spdlog::info("step server: {} more line(s) like \"{}\" were not logged", n, example);
  }
}

// ---------------------------------------------------------------------------------------------
// Transport

void StepServer::Send(const Route& envelope, Json& reply, bool json,
                      const std::optional<ObsSpec>& observation) {
  if (envelope.shm != 0 ? !shm_ : !socket_) return;
  const physics::StateFrame* frame = observation ? state_->Latest() : nullptr;
  if (frame && !observation->cameras.empty()) AddCameras(reply, *observation, *frame);
  std::string text;
  std::span<const std::uint8_t> bytes;
  if (json) {
    if (frame) {
      AddObservation(&reply, tables_, *frame, observation->level, observation->binary,
                     observation->keys, &free_bodies_);
    }
    BinaryToBase64(reply);  // bytes travel as <field>_base64 in JSON text
    text = reply.dump(-1, ' ', false, Json::error_handler_t::replace);
    bytes = {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
  } else {
    // msgpack: the reply's own fields, then the observation written straight from the frame.
    writer_.Clear();
    writer_.Map(reply.size() + (frame ? ObservationEntries(observation->keys) : 0));
    for (const auto& [k, v] : reply.items()) {
      writer_.Key(k);
      writer_.Value(v);
    }
    if (frame) {
      WriteObservationEntries(writer_, tables_, *frame, observation->level, observation->binary,
                              observation->keys, &free_bodies_);
    }
    bytes = {reinterpret_cast<const std::uint8_t*>(writer_.data()), writer_.size()};
  }
  if (envelope.shm != 0) {
    if (!shm_->Has(envelope.shm)) return;  // its client went away
    if (shm_->Reply(envelope.shm, bytes, Clock::now()) || reply.value("op", "") == "error") return;
    // Larger than the channel's reply capacity (the operation took effect): say so instead.
    Json error{{"op", "error"},
               {"code", "reply_too_large"},
               {"message", "a reply of " + std::to_string(bytes.size()) +
                               " bytes does not fit the shared-memory channel; use ZeroMQ for "
                               "this request"}};
    if (reply.contains("seq")) error["seq"] = reply["seq"];
    ++errors_["reply_too_large"];
    Send(envelope, error, json);
    return;
  }
  for (const zmq::message_t& f : envelope.frames) {
    socket_->send(zmq::buffer(f.data(), f.size()), zmq::send_flags::sndmore);
  }
  socket_->send(zmq::buffer(bytes.data(), bytes.size()), zmq::send_flags::dontwait);
}

std::optional<StepServer::ObsSpec> StepServer::ObservationFor(const Request& r) const {
  ObsSpec spec{r.client->level, r.client->binary_arrays,
               r.client->v2026 ? ObsKeys::k2026 : ObsKeys::kOurs};
  if (const auto it = r.body.find("observations"); it != r.body.end()) {
    const auto level = ParseObservationLevel(String(*it, "observations"));
    if (!level) Fail("bad_value", "observations must be minimal, standard or full");
    spec.level = *level;
  }
  if (const auto it = r.body.find("include_cameras"); it != r.body.end() && !it->is_null()) {
    const std::vector<world::CameraStreamInfo> none;
    const auto& streams = cameras_ ? cameras_->Streams() : none;
    if (it->is_boolean()) {
      if (it->get<bool>()) {
        for (std::size_t i = 0; i < streams.size(); ++i) spec.cameras.emplace_back(i, false);
      }
    } else if (it->is_object()) {
      for (const auto& [name, how] : it->items()) {
        if (!how.is_string() || (how != "sync" && how != "latest")) {
          Fail("bad_value", "include_cameras." + name + " must be \"sync\" or \"latest\"");
        }
        // "{art}/{stream}", or a stream name only one articulation has.
        std::vector<std::size_t> found;
        for (std::size_t i = 0; i < streams.size(); ++i) {
          if (streams[i].stream == name ||
              streams[i].articulation + "/" + streams[i].stream == name) {
            found.push_back(i);
          }
        }
        if (found.size() != 1) {
          Fail("bad_value", "include_cameras: " +
                                std::string(found.empty() ? "no camera stream '"
                                                          : "several articulations stream '") +
                                name +
                                "' (name it \"articulation/stream\"; see hello's camera_topics)");
        }
        spec.cameras.emplace_back(found[0], how == "sync");
      }
    } else {
      Fail("bad_value", "include_cameras must be true, false or {stream: \"sync\"|\"latest\"}");
    }
  }
  return spec;
}

void StepServer::AddCameras(Json& reply, const ObsSpec& spec, const physics::StateFrame& frame) {
  Json cameras = Json::object();
  for (const auto& [index, sync] : spec.cameras) {
    const world::CameraStreamInfo& info = cameras_->Streams()[index];
    world::CameraFrame f;
    Json entry{{"mode", info.mode}, {"width", info.width}, {"height", info.height}};
    // A sync frame is rendered from this reply's state (the I/O thread waits for the render
    // thread; the physics thread never waits).
    const bool ok = sync ? cameras_->WaitForStep(index, frame.step, kCameraSyncTimeout, f)
                         : cameras_->Latest(index, f);
    if (ok) {
      entry["frame_id"] = f.frame_id;
      entry["step"] = f.step;
      entry["sim_time"] = f.sim_time;
      entry["render_ms"] = f.render_ms;
      entry["data"] = Json::binary(*f.bytes);
    } else {
      entry["error"] = sync ? "no frame of this step within the timeout" : "no frame yet";
    }
    cameras[info.articulation][info.stream] = std::move(entry);
  }
  reply["cameras"] = std::move(cameras);
}

void StepServer::SendError(const Route& envelope, const Json& seq, bool json,
                           const std::string& code, const std::string& message) {
  ++errors_[code];
  Json reply{{"op", "error"}, {"code", code}, {"message", message}};
  if (!seq.is_null()) reply["seq"] = seq;
  Send(envelope, reply, json);
}

void StepServer::HandleIncoming() {
  HandleShm();
  if (!socket_) return;
  std::vector<zmq::message_t> parts;
  while (true) {
    parts.clear();
    if (!zmq::recv_multipart(*socket_, std::back_inserter(parts), zmq::recv_flags::dontwait)) {
      return;
    }
    if (parts.size() < 2) continue;  // no identity: nothing to answer
    Request r;
    r.now = Clock::now();
    zmq::message_t payload = std::move(parts.back());
    parts.pop_back();
    r.envelope.frames = std::move(parts);  // identity (and the REQ delimiter) echoed back
    r.local = IsLocalPeer(options_.endpoint, payload);
    DecodeAndDispatch(r, {static_cast<const std::uint8_t*>(payload.data()), payload.size()});
  }
}

void StepServer::HandleShm() {
  if (!shm_) return;
  for (const std::string& id : shm_->Sweep(Clock::now())) {
    if (clients_.count(id) == 0) continue;  // said bye already
    CancelQueuedSteps(id, "its shared-memory client went away");
    ForgetClient(id, "its shared-memory client went away");
  }
  shm_->Poll(
      [&](std::uint64_t channel, const std::string&, std::span<const std::uint8_t> bytes) {
        Request r;
        r.now = Clock::now();
        r.envelope.shm = channel;
        r.local = true;
        DecodeAndDispatch(r, bytes);
      },
      [&](std::uint64_t channel) {
        Route route;
        route.shm = channel;
        SendError(route, nullptr, false, "bad_request", "a request length beyond the channel");
      });
}

void StepServer::DecodeAndDispatch(Request& r, std::span<const std::uint8_t> payload) {
  const std::uint8_t* bytes = payload.data();
  r.json = !payload.empty() && (bytes[0] == '{' || bytes[0] == ' ' || bytes[0] == '\n');
  if (payload.size() > options_.limits.max_request_bytes) {
    SendError(r.envelope, nullptr, r.json, "bad_request",
              "request of " + std::to_string(payload.size()) + " bytes (limit " +
                  std::to_string(options_.limits.max_request_bytes) + ")");
    return;
  }
  std::string why;
  if (r.json) {
    if (std::optional<Json> body = wire::DecodeJsonRequest(
            std::string_view(reinterpret_cast<const char*>(bytes), payload.size()), &why)) {
      r.body = std::move(*body);
    }
  } else if (std::optional<Json> body = DecodeMsgpack(bytes, payload.size(), &why)) {
    r.body = std::move(*body);
  }
  if (why.empty() && !r.body.is_object()) why = "the request is not a map";
  if (!why.empty()) {
    SendError(r.envelope, nullptr, r.json, "bad_request",
              std::string(r.json ? "JSON" : "msgpack") + " request refused: " + why);
    return;
  }
  Dispatch(r);
}

void StepServer::Dispatch(Request& r) {
  const Json seq = r.body.contains("seq") ? r.body["seq"] : Json();
  try {
    const auto op_it = r.body.find("op");
    if (op_it == r.body.end()) Fail("missing_op", "the request has no 'op'");
    const std::string op = String(*op_it, "op");
    const OpSpec* spec = nullptr;
    for (const OpSpec& s : Ops()) {
      if (op == s.name) spec = &s;
    }
    if (!spec) {
      if (std::optional<std::string> why = dialect2026::EditorOnly(op)) Fail("unknown_op", *why);
      Fail("unknown_op", "no operation '" + op + "' (see 'meta')");
    }
    // The 2026 dialect (dialect_2026.h): chosen by hello's client_version, then by the session.
    if (op == "hello") {
      r.v2026 = dialect2026::Speaks(r.body);
    } else if (const auto sid = r.body.find("session_id");
               sid != r.body.end() && sid->is_string()) {
      const auto c = clients_.find(sid->get<std::string>());
      r.v2026 = c != clients_.end() && c->second.v2026;
    }
    if (r.v2026) {
      if (op == "configure_controller") r.original = r.body;
      dialect2026::TranslateRequest(r.body);
    }
    if (spec->needs_session) {
      const auto sid = r.body.find("session_id");
      if (sid == r.body.end() || !sid->is_string()) {
        Fail("session_expired", "'" + op + "' needs the session_id from 'hello'");
      }
      const auto c = clients_.find(sid->get<std::string>());
      if (c == clients_.end()) Fail("session_expired", "unknown or expired session; say hello");
      r.client = &c->second;
      r.client->last_seen = r.now;
    }
    for (const char* field : spec->required) Require(r.body, field);
    if (r.client && PendingRequests(r.client->id) >= options_.limits.max_pending_requests) {
      Fail("queue_full", std::to_string(options_.limits.max_pending_requests) +
                             " requests of this session wait for their replies already (the "
                             "limit); wait for them, or cancel queued steps");
    }
    LeaseTake lease;
    const auto overwrite = r.body.find("overwrite");
    if (spec->needs_driver || (spec->overwrite_needs_driver && overwrite != r.body.end() &&
                               Bool(*overwrite, "overwrite"))) {
      const auto force = r.body.find("force");
      lease = CheckDriver(*r.client, force != r.body.end() && Bool(*force, "force"), r.now);
    }
    Outcome out = (this->*spec->handler)(r);
    // The request succeeded (a failure threw above): only now does it take the lease.
    if (lease.take) CommitLease(*r.client, lease);
    if (r.v2026) {  // the reply in the 2026 vocabulary, once it is complete
      out.on_applied = [op, original = std::move(r.original),
                        then = std::move(out.on_applied)](Json& reply) {
        if (then) then(reply);
        dialect2026::TranslateReply(op, original, reply);
      };
    }
    if (out.wait_for == 0) {
      if (out.on_applied) out.on_applied(out.reply);
      if (!seq.is_null()) out.reply["seq"] = seq;
      Send(r.envelope, out.reply, r.json, out.observation);
      return;
    }
    Pending p;
    p.envelope = std::move(r.envelope);
    if (r.client) p.client = r.client->id;
    p.seq = seq;
    p.json = r.json;
    p.op = op;
    p.command = out.wait_for;
    p.steps = out.steps;
    p.outcome = std::move(out);
    p.deadline = r.now + options_.step_timeout;
    pending_.push_back(std::move(p));
  } catch (const Failure& f) {
    SendError(r.envelope, seq, r.json, f.code, f.message);
  } catch (const std::exception& e) {  // a command the engine refused (bad id, size, value)
    SendError(r.envelope, seq, r.json, "bad_value", e.what());
  }
}

bool StepServer::has_ready() const {
  return !pending_.empty() && session_.engine().last_applied_command() >= pending_.front().command;
}

void StepServer::Service(Clock::time_point now) {
  physics::PhysicsEngine& engine = session_.engine();
  while (!pending_.empty()) {
    Pending& p = pending_.front();
    const bool done = engine.last_applied_command() >= p.command;
    if (!done && now < p.deadline) break;  // commands finish in order: later ones wait too
    if (!done) {
      SendError(p.envelope, p.seq, p.json, "step_timeout",
                "'" + p.op + "' did not take effect within the step timeout");
    } else {
      const physics::CommandResult result = engine.WaitForCommand(p.command, Clock::duration(0));
      if (!result.ok() && p.steps > 0 && physics::IsCancelledStep(result.error)) {
        SendError(p.envelope, p.seq, p.json, "cancelled",
                  "the queued steps of this request were cancelled (" +
                      (p.cancelled.empty() ? std::string("by the server") : p.cancelled) +
                      "): " + result.error);
      } else if (!result.ok()) {
        SendError(p.envelope, p.seq, p.json, "bad_value", result.error);
      } else {
        try {
          if (p.outcome.on_applied) p.outcome.on_applied(p.outcome.reply);
          if (!p.seq.is_null()) p.outcome.reply["seq"] = p.seq;
          Send(p.envelope, p.outcome.reply, p.json, p.outcome.observation);
        } catch (const Failure& f) {
          SendError(p.envelope, p.seq, p.json, f.code, f.message);
        }
      }
    }
    // Waiting for a reply is not silence: the lease runs from the reply (an error too).
    if (const auto c = clients_.find(p.client); c != clients_.end()) {
      c->second.last_seen = std::max(c->second.last_seen, now);
    }
    pending_.pop_front();
  }
  // A driver silent for longer than the lease timeout loses the lease.
  if (!driver_.empty() && LeaseExpired(driver_, now)) {
    ReleaseLease("silent for more than " + std::to_string(options_.lease_timeout.count()) + " ms");
  }
}

bool StepServer::LeaseExpired(const std::string& id, Clock::time_point now) const {
  for (const Pending& p : pending_) {
    if (p.client == id) return false;  // waiting for its reply
  }
  const auto it = clients_.find(id);
  return it == clients_.end() || now - it->second.last_seen > options_.lease_timeout;
}

void StepServer::ReleaseLease(const std::string& why) {
  const std::string initial = options_.mode == "direct" ? "direct" : "live";
  const std::string driver = driver_;
  if (mode_ != initial) {
    // Nobody drives the lockstep any more: back to the scene's mode (a paused simulation left
    // behind by a crashed learning loop would look hung).
    ops::SetPaused(session_, initial != "live");
    LogRemote(spdlog::level::info, "lease released, mode",
              fmt::format("step server: driver {} left ({}); {} mode -> {} mode", driver, why,
                          mode_, initial));
    mode_ = initial;
  } else {
    LogRemote(spdlog::level::info, "lease released",
              fmt::format("step server: driver {} left ({})", driver, why));
  }
  driver_.clear();
  replays_.Release(driver);  // its recordings go with its lease
}

StepServer::LeaseTake StepServer::CheckDriver(const Client& c, bool force, Clock::time_point now) {
  if (driver_ == c.id) return {};
  if (!driver_.empty()) {
    if (LeaseExpired(driver_, now)) {
      // As if Service had seen it first: the mode it chose ends, whatever this request does.
      ReleaseLease("silent for more than " + std::to_string(options_.lease_timeout.count()) +
                   " ms");
    } else if (!force) {
      Fail("not_driver", "another client (" + driver_ +
                             ") holds the driver lease; wait, or send force: true to take it");
    } else {
      return {.take = true, .forced = true};
    }
  }
  return {.take = true};
}

void StepServer::CommitLease(const Client& c, const LeaseTake& take) {
  if (take.forced && !driver_.empty() && driver_ != c.id) {
    const std::string old = driver_;
    const std::size_t cancelled = CancelQueuedSteps(old, "the lease was taken over with force");
    const std::size_t released = replays_.Release(old);
    LogRemote(spdlog::level::warn, "lease takeover",
              fmt::format("step server: {} took the lease from {} ({} queued step request(s) "
                          "cancelled, {} replay session(s) released)",
                          c.id, old, cancelled, released));
  }
  driver_ = c.id;
}

std::uint64_t StepServer::QueuedSteps(const std::string& client) const {
  std::uint64_t n = 0;
  for (const Pending& p : pending_) {
    if (p.client == client && p.cancelled.empty()) n += p.steps;
  }
  return n;
}

std::size_t StepServer::PendingRequests(const std::string& client) const {
  return static_cast<std::size_t>(std::count_if(
      pending_.begin(), pending_.end(), [&](const Pending& p) { return p.client == client; }));
}

std::size_t StepServer::CancelQueuedSteps(const std::string& client, const std::string& why) {
  std::uint64_t through = 0;
  std::size_t n = 0;
  bool batch = false;
  for (Pending& p : pending_) {
    if (p.steps == 0 || !p.cancelled.empty() || (!client.empty() && p.client != client)) continue;
    p.cancelled = why;
    through = std::max(through, p.command);
    batch |= p.op.starts_with("batch_");
    ++n;
  }
  // The physics thread drops them: queued ones never run, a running one stops after its
  // current iteration. (Only drivers queue steps, so nobody else's work is among them.)
  if (through > 0) session_.engine().CancelStepsThrough(through);
  if (batch && batch_) batch_->Disarm();  // applied before any later step
  return n;
}

void StepServer::ForgetClient(const std::string& id, const std::string& why) {
  if (driver_ == id) ReleaseLease(why);
  replays_.Release(id);
  if (shm_) shm_->Close(id);  // its channel, if any (after the reply it is serving)
  clients_.erase(id);
}

void StepServer::LogRemote(spdlog::level::level_enum level, std::string_view kind,
                           const std::string& text) {
  std::uint64_t skipped = 0;
  if (!log_limiter_.Admit(kind, Clock::now(), &skipped)) return;
  if (skipped > 0) {
    spdlog::log(level, "{} (and {} more like it since the last one logged)", text, skipped);
  } else {
    spdlog::log(level, "{}", text);
  }
}

// ---------------------------------------------------------------------------------------------
// Observations

const ArticulationTopics& StepServer::Articulation(const Json& name) const {
  const std::string n = String(name, "articulation");
  for (const ArticulationTopics& t : tables_) {
    if (t.name == n) return t;
  }
  Fail("unknown_articulation", "no articulation '" + n + "' in the scene");
}

// ---------------------------------------------------------------------------------------------
// Operations

StepServer::Outcome StepServer::Hello(Request& r) {
  // `require {scene, instance, server_session}`: a client that reached another simulator than
  // the one it was launched for (a port reused by another run) is refused before anything else.
  if (const auto it = r.body.find("require"); it != r.body.end() && !it->is_null()) {
    if (!it->is_object())
      Fail("bad_value", "require must be a map of scene, instance, server_session");
    const std::map<std::string, const std::string*> mine = {
        {"scene", &options_.scene_name},
        {"instance", &options_.instance},
        {"server_session", &options_.server_session}};
    for (const auto& [key, value] : it->items()) {
      const auto m = mine.find(key);
      if (m == mine.end()) {
        Fail("bad_value", "require." + key + ": only scene, instance and server_session");
      }
      const std::string field = "require." + key;
      const std::string wanted = String(value, field.c_str());
      if (wanted != *m->second) {
        Fail("wrong_server", "this server's " + key + " is '" + *m->second + "', not '" + wanted +
                                 "' (scene '" + options_.scene_name + "', instance '" +
                                 options_.instance + "')");
      }
    }
  }
  Client c;
  c.id = NewSessionId(next_client_++);
  c.last_seen = r.now;
  c.v2026 = r.v2026;
  c.route = RouteOf(r.envelope);
  if (const auto it = r.body.find("observations"); it != r.body.end()) {
    const auto level = ParseObservationLevel(String(*it, "observations"));
    if (!level) Fail("bad_value", "observations must be minimal, standard or full");
    c.level = *level;
  }
  if (const auto it = r.body.find("arrays"); it != r.body.end()) {
    const std::string arrays = String(*it, "arrays");
    if (arrays != "binary" && arrays != "list") {
      Fail("bad_value", "arrays must be binary or list (got '" + arrays + "')");
    }
    c.binary_arrays = arrays == "binary";
  }
  if (clients_.size() >= options_.limits.max_clients) {  // forget the longest-silent observer
    auto oldest = clients_.end();
    for (auto it = clients_.begin(); it != clients_.end(); ++it) {
      if (it->first != driver_ &&
          (oldest == clients_.end() || it->second.last_seen < oldest->second.last_seen)) {
        oldest = it;
      }
    }
    if (oldest != clients_.end()) ForgetClient(std::string(oldest->first), "forgotten");
  }
  const mjModel* m = session_.engine().model();
  Json arts = Json::array();
  for (const ArticulationTopics& t : tables_) {
    Json a;
    a["name"] = t.name;
    a["prefix"] = t.name + "_";
    const world::Articulation* wa = session_.FindArticulation(t.name);
    const std::string kind = wa ? wa->config.controller.type : "none";
    a["default_control_mode"] = kind == "none" || kind == "passthrough" ? "raw" : "controller";
    a["controller"] = Json{{"kind", kind}};
    Json joints = Json::array();
    for (std::size_t i = 0; i < t.joints.size(); ++i) {
      const JointTopicEntry& j = t.joints[i];
      const int id = j.id;
      const int width = replay::JointQposWidth(j.type);
      joints.push_back(Json{{"name", t.joint_names[i]},
                            {"id", id},
                            {"type", replay::JointTypeName(j.type)},
                            {"qpos_adr", j.qpos_adr},
                            {"qpos_width", width},
                            {"dof_adr", j.dof_adr},
                            {"dof_width", j.type == mjJNT_FREE   ? 6
                                          : j.type == mjJNT_BALL ? 3
                                                                 : 1},
                            {"limited", m->jnt_limited[id] != 0},
                            {"range", {m->jnt_range[2 * id], m->jnt_range[2 * id + 1]}}});
    }
    a["joints"] = std::move(joints);
    Json actuators = Json::array();
    for (std::size_t i = 0; i < t.actuator_ids.size(); ++i) {
      const int id = t.actuator_ids[i];
      const bool limited = m->actuator_ctrllimited[id] != 0;
      // target_range: what the controller takes (a PD actuator's joint range); ctrlrange: the
      // actuator's own, null when unlimited.
      actuators.push_back(Json{{"name", t.actuator_names[i]},
                               {"id", id},
                               {"target_range", {t.mins[i], t.maxs[i]}},
                               {"ctrlrange", limited ? Json{m->actuator_ctrlrange[2 * id],
                                                            m->actuator_ctrlrange[2 * id + 1]}
                                                     : Json(nullptr)}});
    }
    a["actuators"] = std::move(actuators);
    Json sensors = Json::array();
    for (std::size_t i = 0; i < t.sensors.size(); ++i) {
      sensors.push_back(
          Json{{"name", t.sensor_names[i]}, {"id", t.sensors[i].id}, {"dim", t.sensors[i].dim}});
    }
    a["sensors"] = std::move(sensors);
    a["camera_topics"] = CameraList(cameras_, t.name);
    arts.push_back(std::move(a));
  }
  Json capabilities = Json::array();
  for (const OpSpec& s : Ops()) capabilities.push_back(s.name);
  for (const char* extra : {"json", "binary_arrays", "lease", "seq", "mode:live", "mode:direct",
                            "mode:puppet", "include_assets"}) {
    capabilities.push_back(extra);
  }
  if (shm_) capabilities.push_back("shm");
  if (batch_) capabilities.push_back("batch");
  capabilities.push_back("dialect:urlab_bridge");
  Outcome out;
  out.reply = Json{{"op", "hello_ok"},
                   {"session_id", c.id},
                   {"protocol_version", kProtocolVersion},
                   {"capabilities", std::move(capabilities)},
                   {"urlab_version", kVersion},
                   {"mujoco_version", mj_versionString()},
                   {"mujoco_version_int", mj_version()},
                   {"mode", mode_},
                   {"scene", options_.scene_name},
                   {"instance", options_.instance},
                   {"server_session", options_.server_session},
                   {"articulations", std::move(arts)},
                   {"batch", BatchHello()},
                   {"entities", FreeBodiesHello(free_bodies_)},
                   {"mjb", Json::binary(mjb_)}};
  if (const auto it = r.body.find("include_assets");
      it != r.body.end() && Bool(*it, "include_assets")) {
    if (!assets_) {
      try {
        assets_ = FlattenAssets(world::SceneXml(session_.spec().get()));
      } catch (const std::exception& e) {
        Fail("path_not_readable", std::string("include_assets: ") + e.what());
      }
      spdlog::info("step server: model with {} asset file(s), {} bytes, ready for include_assets",
                   assets_->assets.size(), assets_->bytes);
      // Reading the files held this thread: nobody's lease runs out for that.
      const auto now = Clock::now();
      for (auto& [id, client] : clients_) client.last_seen = std::max(client.last_seen, now);
    }
    out.reply["mjcf_compiled"] = assets_->xml;
    Json files = Json::object();
    for (const auto& [name, bytes] : assets_->assets) {
      files[name] = Json::binary(std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
    }
    out.reply["vfs_assets"] = std::move(files);
  }
  // A client on this host that asks gets a shared-memory channel for this session (not over a
  // channel already, and at most one per possible session).
  if (const auto it = r.body.find("shm"); it != r.body.end() && Bool(*it, "shm") && shm_ &&
                                          r.local && r.envelope.shm == 0 &&
                                          shm_->channels() < options_.limits.max_clients) {
    try {
      out.reply["shm"] = shm_->Offer(c.id, r.now);
    } catch (const std::exception& e) {
      LogRemote(spdlog::level::warn, "shm offer",
                fmt::format("step server: no shared-memory channel for a client: {}", e.what()));
    }
  }
  if (c.v2026) Hello2026(r, out.reply);
  // A new hello over the connection that holds the lease (a client refreshing its session)
  // inherits the lease, and the recordings it loaded; a silent driver has lost it already.
  if (!driver_.empty() && !LeaseExpired(driver_, r.now)) {
    const auto d = clients_.find(driver_);
    if (d != clients_.end() && !c.route.empty() && d->second.route == c.route) {
      LogRemote(spdlog::level::info, "lease inherited",
                fmt::format("step server: session {} inherits the lease of {} (a new hello over "
                            "the same connection)",
                            c.id, driver_));
      replays_.Transfer(driver_, c.id);
      driver_ = c.id;
    }
  }
  clients_[c.id] = c;
  return out;
}

std::string StepServer::RouteOf(const Route& route) {
  if (route.shm != 0) return "shm:" + std::to_string(route.shm);
  if (route.frames.empty()) return "";
  return "zmq:" + route.frames.front().to_string();
}

void StepServer::Hello2026(const Request& r, Json& reply) {
  reply["entities"] =
      dialect2026::Entities(session_, tables_, free_bodies_, cameras_, reply["articulations"]);
  reply["global_cameras"] = dialect2026::GlobalCameras(session_.engine().model(), cameras_);
  if (const auto it = r.body.find("raw_model"); it != r.body.end() && Bool(*it, "raw_model")) {
    reply["raw_model"] = true;
    reply["raw_joints"] = dialect2026::RawJoints(session_);
    reply["raw_actuators"] = dialect2026::RawActuators(session_);
  }
}

std::size_t StepServer::dialect_2026_sessions() const {
  return static_cast<std::size_t>(std::count_if(clients_.begin(), clients_.end(),
                                                [](const auto& c) { return c.second.v2026; }));
}

StepServer::Outcome StepServer::Meta(Request& r) {
  if (r.v2026) {  // ops [{name, category, namespace, required_fields, reply_fields}]
    Json ops = Json::array();
    for (const OpSpec& s : Ops()) {
      Json required = Json::array();
      for (const char* f : s.required) {
        // The 2026 names of the fields it requires.
        std::string_view name = f;
        for (const dialect2026::Field& x : dialect2026::kRequestFields) {
          if (x.op == s.name && x.ours == name) name = x.theirs;
        }
        required.push_back(name);
      }
      Json replies = Json::array();
      std::string_view rest = s.replies;
      while (!rest.empty()) {  // "a, b, ..." as a list
        const std::size_t comma = rest.find(',');
        std::string_view f = rest.substr(0, comma);
        while (f.starts_with(' ')) f.remove_prefix(1);
        if (!f.empty() && f != "...") replies.push_back(f);
        rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
      }
      const dialect2026::OpPlace place = dialect2026::PlaceOf(s.name);
      ops.push_back(Json{{"name", s.name},
                         {"category", place.category},
                         {"namespace", place.ns},
                         {"required_fields", std::move(required)},
                         {"reply_fields", std::move(replies)},
                         {"session", s.needs_session},
                         {"driver", s.needs_driver}});
    }
    return {Json{{"op", "meta_ok"}, {"protocol_version", kProtocolVersion}, {"ops", ops}}};
  }
  Json ops = Json::array();
  for (const OpSpec& s : Ops()) {
    Json required = Json::array();
    for (const char* f : s.required) required.push_back(f);
    ops.push_back(Json{{"name", s.name},
                       {"required", std::move(required)},
                       {"session", s.needs_session},
                       {"driver", s.needs_driver},
                       {"replies", s.replies}});
  }
  return {Json{{"op", "meta_ok"}, {"protocol_version", kProtocolVersion}, {"operations", ops}}};
}

StepServer::Outcome StepServer::Bye(Request& r) {
  const std::string id = r.client->id;
  CancelQueuedSteps(id, "its session said bye");
  ForgetClient(id, "bye");
  r.client = nullptr;
  return {Json{{"op", "bye_ok"}}};
}

StepServer::Outcome StepServer::Cancel(Request& r) {
  const std::size_t n = CancelQueuedSteps(r.client->id, "the client asked with 'cancel'");
  return {Json{{"op", "cancel_ok"}, {"cancelled", n}}};
}

StepServer::Outcome StepServer::Step(Request& r) {
  if (mode_ == "puppet") return PuppetStep(r);
  // State fields belong to puppet mode; silently ignoring them would hide a mode mix-up.
  for (const char* field : {"qpos", "qvel", "time"}) {
    if (r.body.contains(field)) {
      Fail("bad_mode",
           std::string("'") + field + "' in a step is for puppet mode; the mode is " + mode_);
    }
  }
  int n = 1;
  if (const auto it = r.body.find("n_steps"); it != r.body.end()) {
    n = static_cast<int>(RangedNumber(*it, "n_steps"));
  }
  const std::optional<ObsSpec> observation = ObservationFor(r);
  // Controls and forces: the wire's fields to one typed request, checked whole by the operation
  // (ops/targets.h) before anything is published.
  ops::TargetsRequest targets;
  targets.force_steps = n;  // for the whole window, cleared after it
  if (const auto it = r.body.find("per_articulation"); it != r.body.end()) {
    if (!it->is_object()) Fail("bad_value", "per_articulation must be a map");
    for (const auto& [name, entry] : it->items()) {
      ops::RequireArticulation(session_, name);
      if (!entry.is_object()) Fail("bad_value", name + ": a map of ctrl, ctrl_map, xfrc_applied");
      if (entry.contains("qpos") || entry.contains("qvel")) {
        Fail("bad_mode",
             name + ": qpos and qvel in a step are for puppet mode; the mode is " + mode_);
      }
      ops::ArticulationTargets& t = targets.articulations.emplace_back();
      t.articulation = name;
      // control_mode: raw, the values are the actuators' controls; controller (ue_controller in
      // the 2026 dialect), they are the controller's targets. It stays until changed.
      if (const auto m = entry.find("control_mode"); m != entry.end() && !m->is_null()) {
        const std::string mode = String(*m, "control_mode");
        if (mode != "raw" && mode != "controller" && mode != "ue_controller") {
          Fail("bad_value", name + ": control_mode must be raw, controller or ue_controller");
        }
        t.raw = mode == "raw";
      }
      if (const auto c = entry.find("ctrl"); c != entry.end()) t.ctrl = AnyNumbers(*c, "ctrl");
      if (const auto c = entry.find("ctrl_map"); c != entry.end()) {
        if (!c->is_object()) Fail("bad_value", "ctrl_map must be a map of name to value");
        for (const auto& [actuator, value] : c->items()) {
          t.by_name.emplace_back(actuator, AnyNumber(value, name + ": ctrl_map"));
        }
      }
      if (const auto x = entry.find("xfrc_applied"); x != entry.end()) {
        if (!x->is_object()) Fail("bad_value", "xfrc_applied must be a map of body to 6 values");
        for (const auto& [body, wrench] : x->items()) {
          t.wrenches.push_back({body, AnyNumbers(wrench, "xfrc_applied")});
        }
      }
    }
  }
  const ops::CheckedTargets checked = ops::CheckTargets(session_, targets);
  // Bounded work per client: a driver cannot queue more than max_queued_steps ahead.
  const std::uint64_t queued = QueuedSteps(r.client->id);
  if (mode_ == "direct" &&
      queued + static_cast<std::uint64_t>(n) > options_.limits.max_queued_steps) {
    Fail("queue_full", "this session has " + std::to_string(queued) + " steps queued already; " +
                           std::to_string(n) + " more exceed the " + "limit of " +
                           std::to_string(options_.limits.max_queued_steps) +
                           " (wait for the replies, or send 'cancel')");
  }
  ops::ApplyTargets(session_, checked);
  Outcome out;
  out.reply = Json{{"op", "step_ok"}};
  out.observation = observation;
  if (mode_ == "direct" && !StepHere(n)) {
    out.wait_for = ops::Step(session_, n);
    out.steps = static_cast<std::uint64_t>(n);
  }
  return out;
}

bool StepServer::StepHere(int n) {
  // Only a short window with nothing queued before it: this thread serves every client, and a
  // reply waiting for a command must not be overtaken.
  physics::PhysicsEngine& engine = session_.engine();
  const double budget = std::chrono::duration<double>(kMaxStepHere).count();
  if (!pending_.empty() || !engine.paused() || !sync_step_cost_.Affordable(n, budget)) {
    return false;
  }
  const auto start = Clock::now();
  try {
    engine.StepSync(n);
  } catch (const std::exception& e) {
    if (!engine.paused()) return false;  // the loop was unpaused meanwhile: it steps instead
    Fail("bad_value", e.what());
  }
  sync_step_cost_.Measured(std::chrono::duration<double>(Clock::now() - start).count() / n);
  return true;
}

StepServer::Outcome StepServer::Reset(Request& r) {
  // The wire's fields to the typed request; ops::Reset checks it whole before resetting.
  ops::ResetRequest reset;
  if (const auto it = r.body.find("keyframe_name"); it != r.body.end() && !it->is_null()) {
    reset.keyframe = String(*it, "keyframe_name");
  }
  if (const auto it = r.body.find("per_articulation_qpos"); it != r.body.end()) {
    if (!it->is_object()) Fail("bad_value", "per_articulation_qpos must be a map");
    for (const auto& [name, joints] : it->items()) {
      ops::RequireArticulation(session_, name);
      if (!joints.is_object()) Fail("bad_value", name + ": a map of joint to value");
      for (const auto& [joint, value] : joints.items()) {
        reset.joints.push_back({name, joint,
                                value.is_array() ? Numbers(value, "qpos")
                                                 : std::vector<double>{Number(value, "qpos")}});
      }
    }
  }
  // Domain randomisation (step_server_randomize.cc): checked here; the draws are the reset's
  // first action once ops::Reset checked the rest (a keyframe then sets the state again).
  std::optional<world::Session::RandomizedReset> randomized;
  if (std::function<world::Session::RandomizedReset()> draw = RandomizerForReset(r)) {
    reset.randomize = [&randomized, draw = std::move(draw)] {
      randomized = draw();
      return randomized->seq;
    };
  }
  Outcome out;
  out.wait_for = ops::Reset(session_, reset);
  out.reply = Json{{"op", "reset_ok"}};
  if (randomized) out.reply["randomized"] = DrawsJson(randomized->draws);
  out.observation = ObservationFor(r);
  return out;
}

StepServer::Outcome StepServer::Forward(Request& r) {
  Outcome out;
  out.reply = Json{{"op", "forward_ok"}};
  out.wait_for = ops::Forward(session_);
  out.observation = ObservationFor(r);
  return out;
}

StepServer::Outcome StepServer::SetMode(Request& r) {
  const std::string mode = String(r.body["mode"], "mode");
  if (mode != "live" && mode != "direct" && mode != "puppet") {
    Fail("bad_mode", "mode must be live, direct or puppet");
  }
  // Lockstep steps still queued belong to the mode being left: they are cancelled (answered
  // `cancelled`), so this takes effect now and not behind them.
  const std::size_t cancelled = CancelQueuedSteps("", "set_mode " + mode);
  Outcome out;
  out.reply = Json{{"op", "set_mode_ok"},
                   {"previous_mode", mode_},
                   {"current_mode", mode},
                   {"cancelled", cancelled}};
  // Direct: the physics thread waits for step requests (paused between them). Puppet: it never
  // steps; each step request writes the client's state and runs mj_forward.
  out.wait_for = ops::SetPaused(session_, mode != "live");
  mode_ = mode;
  return out;
}

StepServer::Outcome StepServer::SetPaused(Request& r) {
  const bool paused = Bool(r.body["paused"], "paused");
  Outcome out;
  out.reply = Json{{"op", "set_paused_ok"}, {"paused", paused}};
  out.wait_for = ops::SetPaused(session_, paused);
  return out;
}

StepServer::Outcome StepServer::SetSimSpeed(Request& r) {
  const int percent = ops::SetSpeed(session_, Number(r.body["percent"], "percent"));
  return {Json{{"op", "set_sim_speed_ok"}, {"percent", percent}}};
}

StepServer::Outcome StepServer::SetControlSource(Request& r) {
  const std::string name = String(r.body["source"], "source");
  Json reply{{"op", "set_control_source_ok"}, {"source", name}};
  if (const auto it = r.body.find("articulation"); it != r.body.end() && !it->is_null()) {
    const std::string art = String(*it, "articulation");
    ops::SetControlSource(session_, name, art);
    reply["articulation"] = art;
  } else {
    ops::SetControlSource(session_, name);
    reply["articulation"] = nullptr;
  }
  return {reply};
}

StepServer::Outcome StepServer::SetQpos(Request& r) {
  const std::string name = String(r.body["articulation"], "articulation");
  ops::RequireArticulation(session_, name);
  const std::vector<double> q = Numbers(r.body["qpos"], "qpos");
  const ArticulationTopics& t = Articulation(r.body["articulation"]);
  const std::size_t index = static_cast<std::size_t>(&t - tables_.data());
  Outcome out;
  // free_base_shortcut: 7 values placed the free base of an articulation with more joints.
  out.reply =
      Json{{"op", "set_qpos_ok"},
           {"articulation", name},
           {"actor_id", index},
           {"free_base_shortcut", t.free_joint >= 0 && q.size() == 7 && t.qpos_adrs.size() != 7}};
  out.wait_for = ops::SetQpos(session_, name, q);
  out.on_applied = [this, &t](Json& reply) {  // the articulation's qpos as it now is
    const physics::StateFrame* f = state_->Latest();
    Json qpos = Json::array();
    for (int a : t.qpos_adrs) qpos.push_back(f->qpos[static_cast<std::size_t>(a)]);
    reply["qpos"] = std::move(qpos);
  };
  out.observation = ObservationFor(r);
  return out;
}

StepServer::Outcome StepServer::PuppetStep(Request& r) {
  if (const auto it = r.body.find("n_steps"); it != r.body.end() && Number(*it, "n_steps") != 1) {
    Fail("bad_value", "puppet mode does not step: n_steps must be 1 or absent");
  }
  const mjModel* m = session_.engine().model();
  physics::cmd::SetState state;
  // Whole-model vectors: exactly nq, nv, nu values.
  const auto whole = [&](const char* field, int size,
                         std::vector<physics::cmd::SetState::Run>* to) {
    const auto it = r.body.find(field);
    if (it == r.body.end()) return;
    std::vector<double> v = Numbers(*it, field);
    CheckRanges(v, field);
    if (v.size() != static_cast<std::size_t>(size)) {
      Fail("dim_mismatch", std::string(field) + " has " + std::to_string(v.size()) +
                               " values, the model has " + std::to_string(size));
    }
    if (size > 0) to->push_back({0, std::move(v)});
  };
  whole("qpos", m->nq, &state.qpos);
  whole("qvel", m->nv, &state.qvel);
  whole("ctrl", m->nu, &state.ctrl);
  // Per articulation: its own qpos / qvel (joint order) and ctrl (actuator order).
  if (const auto it = r.body.find("per_articulation"); it != r.body.end()) {
    if (!it->is_object()) Fail("bad_value", "per_articulation must be a map");
    for (const auto& item : it->items()) {
      // Plain names: clang 14 cannot capture structured bindings in the lambda below.
      const std::string& name = item.key();
      const Json& entry = item.value();
      const ArticulationTopics& t = Articulation(name);
      if (!entry.is_object()) Fail("bad_value", name + ": a map of qpos, qvel, ctrl");
      for (const auto& field : entry.items()) {
        if (field.key() != "qpos" && field.key() != "qvel" && field.key() != "ctrl") {
          Fail("bad_value",
               name + ": '" + field.key() + "' is not taken in puppet mode (qpos, qvel, ctrl)");
        }
      }
      const auto part = [&](const char* field, const std::vector<int>& adrs,
                            std::vector<physics::cmd::SetState::Run>* to) {
        const auto f = entry.find(field);
        if (f == entry.end()) return;
        const std::vector<double> v = Numbers(*f, field);
        CheckRanges(v, field, name + ": " + field);
        if (v.size() != adrs.size()) {
          Fail("dim_mismatch", name + ": " + field + " has " + std::to_string(v.size()) +
                                   " values, the articulation has " + std::to_string(adrs.size()));
        }
        Append(to, Runs(adrs, v));
      };
      part("qpos", t.qpos_adrs, &state.qpos);
      part("qvel", t.dof_adrs, &state.qvel);
      part("ctrl", t.actuator_ids, &state.ctrl);
    }
  }
  if (const auto it = r.body.find("time"); it != r.body.end()) {
    state.time = RangedNumber(*it, "time");
  }
  CheckQposQuaternions(m, state.qpos, "qpos");
  if (state.qpos.empty() && state.qvel.empty() && state.ctrl.empty() && !state.time) {
    Fail("missing_field",
         "a puppet step needs qpos, qvel, ctrl or time (whole model or "
         "per_articulation)");
  }
  Outcome out;
  out.reply = Json{{"op", "step_ok"}};
  out.observation = ObservationFor(r);
  out.wait_for = session_.engine().Submit(std::move(state));
  return out;
}

}  // namespace urlab::net
