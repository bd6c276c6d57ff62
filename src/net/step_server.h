#pragma once
// The step server of docs/protocol.md: request/reply operations on a ROUTER socket (REQ and DEALER
// clients both work), msgpack or JSON (detected per message, under the size and depth limits of
// request_limits.h; a reply uses the request's encoding), `seq` echoed. Many clients at once:
// observers read; one driver holds a lease for stepping, mode changes and control (released on
// `bye`, after `lease_timeout` without a request, or taken over with `force`; taken only by a
// request that succeeds). A reply that depends on a command is sent only once the physics thread
// has applied it (and the state frame showing it is published). What a client can make the
// server hold is bounded (StepServerLimits: queued steps, waiting requests, loaded recordings);
// queued lockstep steps are cancelled by `cancel`, set_mode and a forced takeover. Files are
// names under one folder (network_files.h); numbers are checked against value_ranges.h; lines a
// client causes are rate-limited. A client on this host may move its session onto a shared-memory
// channel (shm_transport.h), offered in `hello`; its requests and replies are the same bytes.
//
// The server is transport, sessions and leases, and a vocabulary: the OpSpec rows of Ops() map
// each wire operation (its name, required fields, session and lease needs) to a handler that
// reads the wire's fields into the typed request of one operation (urlab/ops/*.h: its one
// validation, whoever calls it), calls it and writes the reply. Step modes and lockstep queues
// belong to the server's clients and stay here; replay playback is ops::ReplaySessions
// (urlab/ops/replay_sessions.h), to which the replay_* operations route.
//
// Threading: the network subsystem's I/O thread only (it owns the socket); built on the main
// thread in BeginPlay.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "core/warning_limiter.h"
#include "net/model_assets.h"
#include "net/msgpack_codec.h"
#include "net/network_files.h"
#include "net/observation.h"
#include "net/shm_transport.h"
#include "net/step_cost.h"
#include "net/topic_table.h"
#include "urlab/ops/replay_sessions.h"
#include "urlab/physics/state_frame.h"
#include "urlab/replay/playback.h"
#include "urlab/replay/player.h"
#include "urlab/replay/recorder.h"
#include "urlab/replay/recording.h"
#include "urlab/world/camera_streams.h"
#include "urlab/world/session.h"
#include "wire/request_limits.h"

namespace urlab::world {
class BatchSubsystem;
struct BatchStepJob;
}  // namespace urlab::world

namespace urlab::net {

// The bounds on what clients may make the server hold (docs/network.md, "Limits").
struct StepServerLimits {
  std::size_t max_request_bytes = wire::kMaxRequestBytes;  // larger: bad_request, not decoded
  std::size_t max_clients = 64;  // hello beyond: the longest-silent observer
                                 // is forgotten
  // Per client: lockstep steps queued (the n_steps of its step requests not answered yet), and
  // requests waiting for their command. Beyond either: queue_full.
  std::size_t max_queued_steps = 100000;
  std::size_t max_pending_requests = 64;
  std::size_t max_replay_sessions = 8;  // recordings loaded at once; beyond: replay_limit
};

struct StepServerOptions {
  std::string endpoint = "tcp://127.0.0.1:5559";
  std::chrono::milliseconds lease_timeout{5000};
  std::chrono::milliseconds step_timeout{30000};  // a reply not ready by then: step_timeout
  std::string mode = "live";                      // initial step mode: live | direct
  StepServerLimits limits;
  // The folder of the files clients name (snapshots, recordings, replays; network_files.h);
  // relative: to the working folder. And the files the running process read, never written.
  std::string files_dir = kDefaultFilesDir;
  std::vector<std::string> inputs;
  // Shared-memory channels offered to local clients that ask in hello (false: never), in
  // `shm.folder` ("": /dev/shm).
  bool shared_memory = true;
  ShmOptions shm;
  // Who this server is, in hello_ok; a client's `hello {require: {...}}` must match them.
  std::string scene_name, instance, server_session;
};

class StepServer {
 public:
  using Clock = std::chrono::steady_clock;
  using Json = nlohmann::ordered_json;

  StepServer(world::Session& session, const std::vector<ArticulationTopics>& tables,
             std::shared_ptr<physics::StateSubscription> state, StepServerOptions options);

  // Creates and binds the ROUTER socket; returns the bound endpoint, "" on failure (why in
  // `failure`; logged when that is null).
  std::string Bind(zmq::context_t& context, std::string* failure = nullptr);
  zmq::socket_t* socket() { return socket_ ? &*socket_ : nullptr; }
  // Reads and answers (or parks) every waiting request.
  void HandleIncoming();
  // Sends the replies whose commands took effect; expires leases and overdue replies.
  void Service(Clock::time_point now);
  bool has_pending() const { return !pending_.empty(); }
  // A parked reply worth spinning for: not a batch step, whose window runs for milliseconds
  // (spinning for it would take a core from the threads stepping it; the doorbell wakes the
  // I/O thread in time).
  bool has_pending_soon() const {
    return !pending_.empty() && !pending_.front().op.starts_with("batch_");
  }
  // True when the oldest parked reply's command took effect (Service would send it).
  bool has_ready() const;
  // Closes the socket (pending replies get `shutting_down`) and ends a replay.
  void Close();

  // The shared-memory side, for the I/O thread's wait: a request waiting on a channel; a
  // client expected to send its next request soon (spin rather than sleep); the wake socket to
  // poll (-1: none); arming before a sleep (true: a request came, do not sleep) and after it.
  bool shm_request_waiting() const { return shm_ && shm_->RequestWaiting(); }
  bool shm_expecting(Clock::time_point now) const { return shm_ && shm_->Expecting(now); }
  int shm_wake_fd() const { return shm_ && shm_->channels() > 0 ? shm_->wake_fd() : -1; }
  bool ShmPrepareSleep() { return shm_ && shm_->PrepareSleep(); }
  void ShmAwake() {
    if (shm_) shm_->Awake();
  }
  // The recorder the recording operations use (nullptr: none; they answer not_ready). Main
  // thread, before the I/O thread starts.
  void SetRecorder(replay::RecorderSubsystem* recorder) { recorder_ = recorder; }
  // The cameras hello lists and `include_cameras` reads (nullptr: none). Main thread, before the
  // I/O thread starts.
  void SetCameras(world::CameraStreams* cameras) { cameras_ = cameras; }
  // Where the replay replay_start plays is shown (the viewer's timeline); nullptr: nowhere. Main
  // thread, before the I/O thread starts.
  void SetPlayback(std::shared_ptr<replay::PlaybackSlot> slot) {
    replays_.SetPlayback(std::move(slot));
  }
  // The batched environments the batch operations drive (nullptr: none; they answer no_batch).
  // Main thread, before the I/O thread starts.
  void SetBatch(world::BatchSubsystem* batch) { batch_ = batch; }

  // Requests answered with an error, per code (I/O thread).
  const std::map<std::string, std::uint64_t>& errors() const { return errors_; }
  // Sessions speaking the 2026 dialect (dialect_2026.h) open now: while there are any, the
  // state/full snapshot carries their keys beside ours (I/O thread).
  std::size_t dialect_2026_sessions() const;

  static constexpr int kProtocolVersion = 1;

 private:
  struct Client {
    std::string id;
    ObsLevel level = ObsLevel::kStandard;
    bool binary_arrays = false;
    Clock::time_point last_seen;
    bool v2026 = false;  // speaks the 2026 dialect (its hello's client_version)
    std::string route;   // the connection its hello came over (ZeroMQ identity or channel)
  };
  // Where a reply goes: the ZeroMQ routing frames to echo, or a shared-memory channel.
  struct Route {
    std::vector<zmq::message_t> frames;
    std::uint64_t shm = 0;  // the channel (0: ZeroMQ)
  };
  struct Request {
    Route envelope;
    bool local = false;  // from this host (loopback or ipc): may be offered shared memory
    Json body;
    bool json = false;  // answer in JSON text
    Client* client = nullptr;
    Clock::time_point now;
    bool v2026 = false;  // the 2026 dialect: translated in before the handler, out after it
    Json original;       // a 2026 request as sent, for replies echoed in its shape
  };
  // The observation a reply carries (taken from the newest state frame when it is sent).
  struct ObsSpec {
    ObsLevel level;
    bool binary;
    ObsKeys keys = ObsKeys::kOurs;
    // include_cameras: streams (indices into cameras_->Streams()) and whether the reply waits
    // for a frame rendered from its own state ("sync") or takes the newest one ("latest").
    std::vector<std::pair<std::size_t, bool>> cameras;
  };
  // What an operation handler decided: a reply now, or one once command `seq` took effect.
  struct Outcome {
    Json reply;                             // the reply (now), or the reply's fixed fields
    std::uint64_t wait_for = 0;             // a command to wait for, 0: reply now
    std::function<void(Json&)> on_applied;  // completes the reply once applied
    std::optional<ObsSpec> observation;     // appended to the reply when it is sent
    std::uint64_t steps = 0;                // wait_for is a lockstep step command of n steps
  };
  struct Pending {
    Route envelope;
    std::string client;  // session id (a driver waiting for its reply keeps its lease)
    Json seq;
    bool json = false;
    std::string op;
    std::uint64_t command = 0;
    std::uint64_t steps = 0;  // a lockstep step command's n (0: not a step)
    std::string cancelled;    // why its steps were cancelled ("": they were not)
    Outcome outcome;
    Clock::time_point deadline;
  };
  using Handler = Outcome (StepServer::*)(Request&);
  struct OpSpec {
    const char* name;
    Handler handler;
    bool needs_session;
    bool needs_driver;
    std::vector<const char*> required;  // fields
    const char* replies;                // reply fields, for meta
    // The request may say `overwrite: true` (replace an existing file), which needs the lease.
    bool overwrite_needs_driver = false;
  };
  // What the lease check decided for a request: the client takes the lease once the request
  // succeeded (a failing request takes nothing).
  struct LeaseTake {
    bool take = false;    // the client does not hold it yet
    bool forced = false;  // taken from a live driver with force: true
  };
  static const std::vector<OpSpec>& Ops();

  void Dispatch(Request& r);
  // The connection a request came over (a hello from the driver's connection inherits its lease).
  static std::string RouteOf(const Route& route);
  // Hello's additions for a 2026 client (entities array, global_cameras, raw tables).
  void Hello2026(const Request& r, Json& reply);
  // Decodes a request's bytes (msgpack or JSON text, within the limits) and dispatches it, or
  // answers bad_request.
  void DecodeAndDispatch(Request& r, std::span<const std::uint8_t> payload);
  void Send(const Route& envelope, Json& reply, bool json,
            const std::optional<ObsSpec>& observation = std::nullopt);
  // The reply's `cameras` map ({art: {stream: frame}}) for the streams `spec` names, showing
  // `frame` (sync) or the newest rendered (latest).
  void AddCameras(Json& reply, const ObsSpec& spec, const physics::StateFrame& frame);
  // The observation of a request's client (its level unless the request names one).
  std::optional<ObsSpec> ObservationFor(const Request& r) const;
  void SendError(const Route& envelope, const Json& seq, bool json, const std::string& code,
                 const std::string& message);
  // The lease: throws not_driver unless `c` may drive. An expired lease is released here; taking
  // it (CommitLease) waits until the request succeeded.
  LeaseTake CheckDriver(const Client& c, bool force, Clock::time_point now);
  // `c` holds the lease from now on; a driver it was forced from loses its queued steps and its
  // replay sessions.
  void CommitLease(const Client& c, const LeaseTake& take);
  // Cancels the lockstep steps queued by `client` ("" : by every client): their requests are
  // answered `cancelled` once the physics thread dropped them. Returns how many requests.
  std::size_t CancelQueuedSteps(const std::string& client, const std::string& why);
  // The steps and requests `client` has queued.
  std::uint64_t QueuedSteps(const std::string& client) const;
  std::size_t PendingRequests(const std::string& client) const;
  // Forgets a client: its replay sessions are released (bye, evicted, expired).
  void ForgetClient(const std::string& id, const std::string& why);
  // Logs a line a client's request caused, at most once a second per `kind` (the rest counted
  // in the next line of that kind).
  void LogRemote(spdlog::level::level_enum level, std::string_view kind, const std::string& text);
  // True when `id` is silent past the lease timeout and has no reply waiting.
  bool LeaseExpired(const std::string& id, Clock::time_point now) const;
  // Frees the lease; a lockstep or puppet mode the driver chose goes back to the initial mode.
  void ReleaseLease(const std::string& why);
  const ArticulationTopics& Articulation(const Json& name) const;
  std::string Mode() const { return mode_; }

  // Operations.
  Outcome Hello(Request& r);
  Outcome Meta(Request& r);
  Outcome Bye(Request& r);
  Outcome Step(Request& r);
  // Direct mode: runs a short lockstep window of `n` steps on this thread (the physics thread
  // sleeps between windows), so a round trip needs no hand-over to the physics thread and back
  // (on 2 cores, client, I/O and physics threads all waiting hot cost each other the CPU). False
  // (nothing done) for a window longer than kMaxStepHere at the measured step cost, while
  // replies wait for commands, or while the loop runs: the physics thread steps it then.
  bool StepHere(int n);
  static constexpr auto kMaxStepHere = std::chrono::microseconds(2000);
  StepCostEstimate sync_step_cost_;  // wall seconds per step of StepHere windows
  // A batch step, like StepHere: on this thread and the batch's workers (the physics thread
  // sleeps), for a window up to kMaxBatchHere at the measured cost; false: nothing done.
  bool BatchStepHere(world::BatchSubsystem& b, const std::shared_ptr<world::BatchStepJob>& job);
  static constexpr auto kMaxBatchHere = std::chrono::milliseconds(25);
  StepCostEstimate batch_step_cost_;  // wall seconds per step of batch windows (either thread)
  Outcome PuppetStep(Request& r);
  Outcome Reset(Request& r);
  Outcome Forward(Request& r);
  Outcome SetMode(Request& r);
  Outcome SetPaused(Request& r);
  Outcome SetSimSpeed(Request& r);
  Outcome SetControlSource(Request& r);
  Outcome SetQpos(Request& r);
  Outcome SetMocapPose(Request& r);
  Outcome ReadMocapPose(Request& r);
  Outcome ListKeyframes(Request& r);
  Outcome GetContacts(Request& r);
  Outcome SetSimOptions(Request& r);
  Outcome GetCounters(Request& r);
  Outcome SetTwist(Request& r);
  Outcome FireLauncher(Request& r);
  Outcome ConfigureController(Request& r);
  Outcome Cancel(Request& r);
  // Camera streams on or off (step_server_camera_ops.cc).
  Outcome SetCameraStreaming(Request& r);
  // Emulated latency (step_server_latency_ops.cc).
  Outcome SetLatency(Request& r);
  Outcome GetLatency(Request& r);
  Outcome SetCameraDelay(Request& r);  // step_server_camera_ops.cc
  // Domain randomisation (step_server_randomize.cc): when the request or the scene asks for
  // draws, checks the request's seed and ranges (refused while recording) and returns what
  // draws them and resets (Session::ResetRandomized); empty when nothing is to be drawn.
  std::function<world::Session::RandomizedReset()> RandomizerForReset(const Request& r);
  static Json DrawsJson(const world::RandomDraws& draws);
  // Recorder, snapshot and replay operations (step_server_recorder_ops.cc). File names are
  // names under options.files_dir (network_files.h).
  replay::Recorder& RequireRecorder();
  // Every client's lease runs from now (after a blocking file operation on this thread).
  void RefreshLeases();
  // Runs `op` (file work that may block this thread), then refreshes the leases, also when it
  // fails. Its errors become replies: a RecorderError by its code, a RecordingError as bad_value
  // (another model) or path_not_readable, any other exception as `other_errors` (rethrown when
  // null).
  void RunFileOp(const std::function<void()>& op, const char* other_errors = nullptr);
  Outcome RecordingStart(Request& r);
  Outcome RecordingStop(Request& r);
  Outcome RecordingSave(Request& r);
  Outcome RecordingClear(Request& r);
  Outcome RecordingStatus(Request& r);
  Outcome SnapshotSave(Request& r);
  Outcome SnapshotLoad(Request& r);
  Outcome ReplayLoad(Request& r);
  Outcome ReplayListSessions(Request& r);
  Outcome ReplaySetActive(Request& r);
  Outcome ReplayStart(Request& r);
  Outcome ReplayStop(Request& r);
  Outcome ReplayStatus(Request& r);
  Outcome ReplayUnload(Request& r);
  // Batched environments (step_server_batch_ops.cc).
  world::BatchSubsystem& RequireBatch();
  Json BatchHello() const;  // hello's `batch` ({envs, threads}; null without a batch)
  Outcome BatchInfo(Request& r);
  Outcome BatchStep(Request& r);
  Outcome BatchReset(Request& r);
  // The path of the request's `path` for writing (NetworkFiles::ForWriting with its
  // `overwrite`), never the file a running recording writes.
  std::string WritablePath(const Request& r);

  world::Session& session_;
  const std::vector<ArticulationTopics>& tables_;
  const std::vector<FreeBodyEntry> free_bodies_;  // of no articulation (net/free_bodies.h)
  std::shared_ptr<physics::StateSubscription> state_;
  StepServerOptions options_;
  std::optional<zmq::socket_t> socket_;
  std::unique_ptr<ShmTransport> shm_;  // shared-memory channels (null: not offered)
  // Reads the requests waiting on the shared-memory channels; closes those of clients gone.
  void HandleShm();
  std::map<std::string, Client> clients_;
  std::string driver_;  // session id holding the lease, "" when free
  std::string mode_;
  std::deque<Pending> pending_;
  std::map<std::string, std::uint64_t> errors_;
  std::uint64_t next_client_ = 1;
  std::vector<std::uint8_t> mjb_;          // the compiled model (mj_saveModel), for hello
  std::optional<ModelWithAssets> assets_;  // for hello's include_assets, built on first use
  MsgpackWriter writer_;                   // reply bytes, reused
  replay::RecorderSubsystem* recorder_ = nullptr;
  world::CameraStreams* cameras_ = nullptr;
  NetworkFiles files_;                    // the names clients give, under files_dir
  internal::WarningLimiter log_limiter_;  // lines clients cause (LogRemote)
  world::BatchSubsystem* batch_ = nullptr;
  // Recordings loaded for replay and the one playing (released with their client's lease, its
  // session, its next load or replay_unload): the replay_* operations route here.
  ops::ReplaySessions replays_;
};

}  // namespace urlab::net
