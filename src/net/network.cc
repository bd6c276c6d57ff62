#include "urlab/net/network.h"

#include <pthread.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <future>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <thread>
#include <unordered_map>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "core/spin_wait.h"
#include "net/camera_list.h"
#include "net/loopback.h"
#include "net/msgpack_codec.h"
#include "net/observation.h"
#include "net/port_owner.h"
#include "net/step_server.h"
#include "net/topic_table.h"
#include "urlab/core/doorbell.h"
#include "urlab/core/error.h"
#include "urlab/ops/controllers.h"
#include "urlab/ops/error.h"
#include "urlab/ops/targets.h"
#include "urlab/world/scene.h"
#include "urlab/world/session.h"

namespace urlab::net {

namespace {

using Clock = std::chrono::steady_clock;

// The longest the I/O thread sleeps with nothing to do (it wakes at once for messages and frames).
constexpr auto kIdlePeriod = std::chrono::milliseconds(50);
// How long the I/O thread watches for a parked reply without sleeping.
constexpr auto kReplySpin = std::chrono::milliseconds(1);
// While spinning for a shared-memory request, the sockets are polled at most this often.
constexpr auto kSocketCheck = std::chrono::microseconds(20);
constexpr auto kPausedRepublish = std::chrono::milliseconds(100);  // at most 10 Hz while paused
constexpr auto kPausedInfo = std::chrono::seconds(1);
constexpr auto kDropLogPeriod = std::chrono::seconds(1);

// Frames the I/O thread may fall behind the physics thread before it skips to the newest.
constexpr std::size_t kMaxBacklog = 16;

std::string InfoJson(const ArticulationTopics& t, const world::CameraStreams* cameras) {
  nlohmann::ordered_json j;
  j["type"] = "actuator_list";
  j["robot"] = t.name;
  j["names"] = t.actuator_names;
  j["ids"] = t.actuator_ids;
  j["mins"] = t.mins;
  j["maxs"] = t.maxs;
  j["camera_list"] = CameraList(cameras, t.name);
  return j.dump();
}

// The counter a refused control message counts in.
wire::Drop ControlDrop(ops::TargetsFault fault) {
  switch (fault) {
    case ops::TargetsFault::kCount:
      return wire::Drop::kTooMany;
    case ops::TargetsFault::kOutOfRange:
      return wire::Drop::kBadNumber;
    case ops::TargetsFault::kUnknownActuator:
    case ops::TargetsFault::kUnknownArticulation:  // (the topic names the articulation)
    case ops::TargetsFault::kUnknownBody:          // (a control message has no bodies)
      break;
  }
  return wire::Drop::kForeignActuator;
}

}  // namespace

NetworkOptions NetworkOptionsFromScene(const NetworkConfig& config) {
  NetworkOptions o;
  o.state = config.state;
  o.control = config.control;
  o.info = config.info;
  o.rpc = config.rpc;
  o.step_mode = config.step_mode;
  o.full_state = config.full_state;
  o.files_dir = config.files_dir;
  o.max_queued_steps = config.max_queued_steps;
  return o;
}

std::uint64_t NetworkCounters::total_drops() const {
  std::uint64_t n = 0;
  for (std::uint64_t d : drops) n += d;
  return n;
}

struct NetworkSubsystem::Impl {
  enum class Kind { kControl, kSetGains };
  struct Route {
    std::size_t articulation;
    Kind kind;
  };

  NetworkOptions options;
  std::vector<ArticulationTopics> tables;
  std::vector<FreeBodyEntry> free_bodies;  // of no articulation: state/full's entities, scene
  std::unordered_map<std::string, Route> routes;  // inbound topic -> articulation and kind
  std::shared_ptr<physics::StateRing> ring;
  std::shared_ptr<Doorbell> bell = std::make_shared<Doorbell>();  // frames and command results
  std::unique_ptr<StepServer> server;  // built on the main thread, then used by the I/O thread
  std::vector<std::string> info_messages;
  const mjModel* model = nullptr;
  world::Session* session = nullptr;  // control: ops::SetTargets, set_gains: ops::SetGains

  std::thread thread;
  std::atomic<bool> stop{false};
  std::array<std::atomic<std::uint64_t>, wire::kNumDrops> drops{};
  std::atomic<std::uint64_t> controls_applied{0}, gains_applied{0}, steps_published{0},
      info_published{0}, frames_skipped{0}, state_messages{0};

  // ---- I/O thread only ----
  std::optional<zmq::context_t> context;
  std::optional<zmq::socket_t> pub, sub, info;
  // The state socket is an XPUB (SUB clients see a PUB), so the topic prefixes subscribers ask
  // for are known here and a topic nobody wants is not even encoded.
  std::set<std::string> prefixes;
  bool wanted_dirty = true;
  std::vector<std::vector<char>> joint_wanted, sensor_wanted;  // per articulation, per topic
  std::vector<char> twist_wanted, actions_wanted;              // per articulation
  bool full_wanted = false;
  SpinWait spin;  // for parked replies (gives up under CPU contention)
  // For a request from a client on shared memory, which lands within a microsecond of the reply:
  // SpinTight (pause instructions, a yield every few turns only: a system call on every turn
  // would add its length to every round trip).
  SpinWait spin_quick;
  physics::StateFrame frame;  // the newest frame taken from the ring
  bool have_frame = false;
  std::string payload;
  std::optional<ObsLevel> full_state;  // the state/full level, none: not published
  MsgpackWriter full_writer;
  std::vector<std::pair<std::int32_t, float>> control_scratch;
  ops::TargetsRequest control_request;  // one articulation, reused: no allocation per message
  ops::CheckedTargets control_checked;
  std::vector<wire::GainPatch> gains_scratch;
  std::array<std::uint64_t, wire::kNumDrops> logged_drops{};
  Clock::time_point last_drop_log{}, last_republish{}, last_paused_info{};
  std::uint64_t next_info_step = 0;  // discovery: every 50 steps for the first 2500, then 500

  void Drop(wire::Drop d) { drops[static_cast<std::size_t>(d)].fetch_add(1); }

  // Creates and binds a socket; on failure logs the endpoint (and who holds the port) and
  // returns nothing. Returns the bound endpoint (a wildcard port resolved).
  std::string Bind(std::optional<zmq::socket_t>* slot, zmq::socket_type type, const char* what,
                   const std::string& endpoint, std::vector<std::string>* failures) {
    if (endpoint.empty()) return "";
    zmq::socket_t s(*context, type);
    s.set(zmq::sockopt::linger, 0);
    if (type == zmq::socket_type::pub || type == zmq::socket_type::xpub) {
      s.set(zmq::sockopt::sndhwm, 10000);
    }
    try {
      s.bind(endpoint);
    } catch (const zmq::error_t& e) {
      const std::string why = DescribeBindFailure(what, endpoint, e.num(), e.what());
      failures->push_back(why);
      if (!options.require_bind) spdlog::error("network: {}; running without it", why);
      return "";
    }
    const std::string bound = s.get(zmq::sockopt::last_endpoint);
    if (!IsLoopbackEndpoint(endpoint)) {
      if (type == zmq::socket_type::sub) {
        spdlog::warn(
            "network: the {} socket accepts connections from other hosts ({}): anyone who can "
            "reach it may send controls and gains",
            what, endpoint);
      } else {
        spdlog::info("network: the {} socket publishes to other hosts ({})", what, endpoint);
      }
    }
    *slot = std::move(s);
    return bound;
  }

  void Send(zmq::socket_t& s, std::string_view topic, std::string_view body) {
    // Non-blocking: a PUB socket drops at its high-water mark instead of blocking.
    s.send(zmq::buffer(topic), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
    s.send(zmq::buffer(body), zmq::send_flags::dontwait);
  }

  void SendState(std::string_view topic, std::string_view body) {
    Send(*pub, topic, body);
    state_messages.fetch_add(1, std::memory_order_relaxed);
  }

  // Subscription changes on the state socket: 1 + prefix subscribes, 0 + prefix unsubscribes
  // (ZeroMQ passes on the first subscription to a prefix and the last unsubscription only).
  void DrainSubscriptions() {
    if (!pub) return;
    zmq::message_t m;
    while (pub->recv(m, zmq::recv_flags::dontwait)) {
      if (m.size() == 0) continue;
      const auto* b = static_cast<const char*>(m.data());
      const std::string prefix(b + 1, m.size() - 1);
      if (b[0] == 1) {
        prefixes.insert(prefix);
      } else if (b[0] == 0) {
        prefixes.erase(prefix);
      }
      wanted_dirty = true;
    }
  }

  // The every-step ring runs only while someone subscribes to the state socket: without a
  // subscriber no state topic is sent, and copying every step's state into the ring cost a
  // lockstep window about 1.5 us a step (shm_n10 0.93 against 0.95 without it). Switched on
  // while paused, the engine publishes a frame at once (an Inspect command), so that the late
  // subscriber gets the paused state.
  void UpdateStreaming() {
    const bool on = !prefixes.empty();
    if (on == ring->active()) return;
    ring->SetActive(on);
    if (on && session->engine().paused()) {
      session->engine().Submit(physics::cmd::Inspect{[](const mjModel*, const mjData*) {},
                                                     "network: a state subscriber"});
    }
  }

  // The info topic's schedule (discovery): every 50 steps for the first 2500, then every 500,
  // by the step of the newest frame, or the engine's step counter while the ring is off.
  void InfoAtStep(std::uint64_t step) {
    if (step < next_info_step) return;
    PublishInfo();
    next_info_step = step + (step < 2500 ? 50 : 500);
  }
  // And while paused, every kPausedInfo.
  void InfoWhilePaused(Clock::time_point now) {
    if (now - last_paused_info < kPausedInfo) return;
    PublishInfo();
    last_paused_info = now;
  }

  bool Wanted(std::string_view topic) const {
    for (const std::string& p : prefixes) {
      if (topic.starts_with(p)) return true;
    }
    return false;
  }

  void UpdateWanted() {
    if (!wanted_dirty) return;
    wanted_dirty = false;
    joint_wanted.assign(tables.size(), {});
    sensor_wanted.assign(tables.size(), {});
    twist_wanted.assign(tables.size(), 0);
    actions_wanted.assign(tables.size(), 0);
    for (std::size_t i = 0; i < tables.size(); ++i) {
      for (const JointTopicEntry& j : tables[i].joints) joint_wanted[i].push_back(Wanted(j.topic));
      for (const SensorTopicEntry& x : tables[i].sensors) {
        sensor_wanted[i].push_back(Wanted(x.topic));
      }
      twist_wanted[i] = Wanted(tables[i].twist_topic);
      actions_wanted[i] = Wanted(tables[i].actions_topic);
    }
    full_wanted = Wanted(wire::kFullStateTopic);
  }

  // {art}/twist while a twist controller is attached, {art}/actions while a bit is held: read
  // from the controller (any thread), as the description's broadcaster reads GetTwist().
  void PublishTwist(std::size_t ti) {
    const ArticulationTopics& t = tables[ti];
    if (!t.twist || !t.twist->attached()) return;
    if (twist_wanted[ti]) {
      const control::Twist tw = t.twist->twist();
      payload.clear();
      wire::AppendTwist(&payload, tw.vx, tw.vy, tw.yaw_rate);
      SendState(t.twist_topic, payload);
    }
    const std::uint32_t actions = t.twist->actions();
    if (actions != 0 && actions_wanted[ti]) {
      payload.clear();
      wire::AppendActions(&payload, static_cast<std::int32_t>(actions));
      SendState(t.actions_topic, payload);
    }
  }

  void PublishState(const physics::StateFrame& f) {
    if (!pub) return;
    UpdateWanted();  // (subscriptions are drained once per turn of Run, not per frame)
    for (std::size_t ti = 0; ti < tables.size(); ++ti) {
      const ArticulationTopics& t = tables[ti];
      for (std::size_t ji = 0; ji < t.joints.size(); ++ji) {
        if (!joint_wanted[ti][ji]) continue;
        const JointTopicEntry& j = t.joints[ji];
        payload.clear();
        const double* q = f.qpos.data() + j.qpos_adr;
        const double* v = f.qvel.data() + j.dof_adr;
        const double* a = f.qacc.data() + j.dof_adr;
        switch (j.type) {
          case mjJNT_FREE:
            wire::AppendBaseState(&payload, q, v);
            break;
          case mjJNT_BALL:
            wire::AppendBallJoint(&payload, j.id, q, v, a);
            break;
          default:
            wire::AppendJoint(&payload, j.id, *q, *v, *a);
            break;
        }
        SendState(j.topic, payload);
      }
      for (std::size_t si = 0; si < t.sensors.size(); ++si) {
        if (!sensor_wanted[ti][si]) continue;
        const SensorTopicEntry& s = t.sensors[si];
        payload.clear();
        wire::AppendSensor(&payload, s.id,
                           std::span(f.sensordata.data() + s.adr, static_cast<std::size_t>(s.dim)));
        SendState(s.topic, payload);
      }
      PublishTwist(ti);
    }
    if (full_state && full_wanted) {  // state/full: the step server's observation map, msgpack
      // `op: state_full` names the snapshot; while a session speaks the 2026 dialect, its keys
      // (arts, scene) travel beside ours (docs/protocol.md, "The 2026 dialect").
      const ObsKeys keys =
          server && server->dialect_2026_sessions() > 0 ? ObsKeys::kBoth : ObsKeys::kOurs;
      full_writer.Clear();
      full_writer.Map(ObservationEntries(keys) + 1);
      full_writer.Key("op");
      full_writer.Str("state_full");
      WriteObservationEntries(full_writer, tables, f, *full_state, false, keys, &free_bodies);
      SendState(wire::kFullStateTopic, std::string_view(full_writer.data(), full_writer.size()));
    }
  }

  void PublishInfo() {
    if (!info) return;
    for (const std::string& m : info_messages) {
      info->send(zmq::buffer(m), zmq::send_flags::dontwait);
      info_published.fetch_add(1);
    }
  }

  void HandleControl(ArticulationTopics& t, std::string_view body) {
    if (auto d = wire::DecodeControl(body, &control_scratch)) return Drop(*d);
    // The operation the step server's step and the viewer's sliders use: one validation, one
    // whole frame (every value of the message or none).
    if (control_request.articulations.empty()) control_request.articulations.emplace_back();
    ops::ArticulationTargets& a = control_request.articulations[0];
    a.articulation = t.name;
    a.by_id.assign(control_scratch.begin(), control_scratch.end());
    try {
      ops::CheckTargets(*session, control_request, &control_checked);
    } catch (const ops::TargetsError& e) {
      return Drop(ControlDrop(e.fault));
    }
    ops::ApplyTargets(*session, control_checked);
    controls_applied.fetch_add(1);
  }

  void HandleSetGains(ArticulationTopics& t, std::string_view body) {
    if (auto d = wire::DecodeSetGains(body, &gains_scratch)) return Drop(*d);
    // The operation configure_controller uses: names resolved, all or nothing, into the
    // command frames (so the recorder records them).
    ops::GainsRequest request;
    for (const wire::GainPatch& p : gains_scratch) {
      request.named.push_back({p.name, {p.kp, p.kv, p.torque_limit}});
    }
    try {
      ops::SetGains(*session, t.name, request);
    } catch (const ops::OpError& e) {
      return Drop(e.code == "no_controller" ? wire::Drop::kNoController : wire::Drop::kUnknownName);
    }
    gains_applied.fetch_add(1);
  }

  void DrainControl() {
    if (!sub) return;
    std::vector<zmq::message_t> parts;
    while (true) {
      parts.clear();
      const auto n =
          zmq::recv_multipart(*sub, std::back_inserter(parts), zmq::recv_flags::dontwait);
      if (!n) return;
      if (parts.size() != 2) {
        Drop(wire::Drop::kBadFraming);
        continue;
      }
      const auto it = routes.find(std::string(parts[0].to_string_view()));
      if (it == routes.end()) {
        Drop(wire::Drop::kUnknownTopic);
        continue;
      }
      ArticulationTopics& t = tables[it->second.articulation];
      if (it->second.kind == Kind::kControl) {
        HandleControl(t, parts[1].to_string_view());
      } else {
        HandleSetGains(t, parts[1].to_string_view());
      }
    }
  }

  void LogDrops(Clock::time_point now) {
    if (now - last_drop_log < kDropLogPeriod) return;
    last_drop_log = now;
    std::string what;
    for (int i = 0; i < wire::kNumDrops; ++i) {
      const std::uint64_t n = drops[static_cast<std::size_t>(i)].load();
      const std::uint64_t delta = n - logged_drops[static_cast<std::size_t>(i)];
      if (delta == 0) continue;
      logged_drops[static_cast<std::size_t>(i)] = n;
      what += fmt::format("{}{} {}", what.empty() ? "" : ", ",
                          wire::DropName(static_cast<wire::Drop>(i)), delta);
    }
    if (!what.empty())
      spdlog::warn("network: dropped inbound message(s) in the last second: {}", what);
  }

  // Sleeps until a socket has a message, the physics thread published a frame (or finished a
  // command), or the idle period ends (paused republishing, lease expiry, drop logging).
  void Sleep() {
    const auto work = [&] {
      return ring->size() > 0 || (server && (server->has_ready() || server->shm_request_waiting()));
    };
    if (work() || stop.load(std::memory_order_acquire)) return;
    zmq::pollitem_t items[5];
    int n = 0;
    items[n++] = {nullptr, bell->fd(), ZMQ_POLLIN, 0};
    if (pub) items[n++] = {static_cast<void*>(*pub), 0, ZMQ_POLLIN, 0};  // subscriptions
    if (sub) items[n++] = {static_cast<void*>(*sub), 0, ZMQ_POLLIN, 0};
    if (server && server->socket()) {
      items[n++] = {static_cast<void*>(*server->socket()), 0, ZMQ_POLLIN, 0};
    }
    if (server && server->shm_wake_fd() >= 0) {
      items[n++] = {nullptr, server->shm_wake_fd(), ZMQ_POLLIN, 0};
    }
    // A parked reply (a lockstep window under way) is due within a few steps, and a client on
    // shared memory that just got its reply sends the next request soon: watch for them without
    // sleeping for a while, since a wake-up from poll costs more than the round trip. The
    // doorbell is not armed meanwhile (the physics thread then makes no system call to ring it),
    // and sockets are polled every few turns only (a system call each).
    if (server && server->has_pending_soon()) {
      unsigned turn = 0;
      if (spin.Spin(kReplySpin, [&] {
            if (work()) return true;
            if (!server->has_pending() && !server->shm_expecting(Clock::now())) return true;
            return (++turn & 7) == 0 &&
                   zmq::poll(items, static_cast<std::size_t>(n), std::chrono::milliseconds(0)) > 0;
          })) {
        return;
      }
    } else if (server && server->shm_expecting(Clock::now())) {
      auto polled = Clock::now();
      if (spin_quick.SpinTight(kReplySpin, [&] {
            if (work()) return true;
            const auto now = Clock::now();
            if (!server->shm_expecting(now)) return true;
            if (now - polled < kSocketCheck) return false;
            polled = now;
            return zmq::poll(items, static_cast<std::size_t>(n), std::chrono::milliseconds(0)) > 0;
          })) {
        return;
      }
    }
    bell->Arm();
    // Checked after arming: work that arrived before Arm() is seen here, work after it rings.
    // Clients on shared memory send a wake-up while the server sleeps (checked once more after
    // telling them).
    if (work() || stop.load(std::memory_order_acquire) || (server && server->ShmPrepareSleep())) {
      bell->Clear();
      return;
    }
    zmq::poll(items, static_cast<std::size_t>(n), kIdlePeriod);
    if (server) server->ShmAwake();
    bell->Clear();
  }

  void Run(std::promise<Endpoints>* ready) {
    Endpoints bound;
    // Under contention the physics thread comes first: this thread (and ZeroMQ's I/O thread,
    // created below, which inherits it) runs at a lower priority. Late state is dropped anyway.
    if (options.io_nice > 0) {
      errno = 0;
      const int now = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
      if (errno == 0) setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), now + options.io_nice);
    }
    try {
      context.emplace(1);
      bound.state = Bind(&pub, zmq::socket_type::xpub, "state", options.state, &bound.failures);
      bound.control =
          Bind(&sub, zmq::socket_type::sub, "control", options.control, &bound.failures);
      bound.info = Bind(&info, zmq::socket_type::pub, "info", options.info, &bound.failures);
      if (sub) sub->set(zmq::sockopt::subscribe, "");
      if (server) {
        std::string why;
        bound.rpc = server->Bind(*context, &why);
        if (!why.empty()) {
          bound.failures.push_back(why);
          if (!options.require_bind) spdlog::error("step server: {}; running without it", why);
        }
      }
    } catch (const std::exception& e) {
      bound.failures.push_back(e.what());
      spdlog::error("network: {}", e.what());
    }
    ready->set_value(bound);
    while (!stop.load(std::memory_order_acquire)) {
      // 1. Inbound first (controls and requests are what clients wait on).
      DrainControl();
      DrainSubscriptions();
      UpdateStreaming();
      if (server) {
        server->HandleIncoming();
        // 2. Replies whose commands took effect (a lockstep reply as soon as its window ends).
        server->Service(Clock::now());
      }
      // 3. Streaming. Behind by more than kMaxBacklog steps (the physics runs faster than the
      // topics can be sent), skip to the newest frames: late state is worse than missing state.
      const std::size_t queued = ring->size();
      for (std::size_t i = kMaxBacklog; i < queued; ++i) {
        ring->Pop();
        frames_skipped.fetch_add(1);
      }
      bool got = false;
      while (ring->TryPop(&frame)) {
        got = have_frame = true;
        PublishState(frame);
        steps_published.fetch_add(1);
        InfoAtStep(frame.step);
        DrainControl();  // a long backlog must not starve inbound messages
        if (server) server->HandleIncoming();
      }
      const auto now = Clock::now();
      if (!ring->active()) {  // no frames: the engine's own counters
        InfoAtStep(session->engine().step_count());
        if (session->engine().paused()) InfoWhilePaused(now);
      } else if (!got && have_frame && frame.paused) {
        if (now - last_republish >= kPausedRepublish) {  // late subscribers see a paused state
          PublishState(frame);
          last_republish = now;
        }
        InfoWhilePaused(now);
      }
      LogDrops(now);
      Sleep();
    }
    LogDrops(Clock::now() + kDropLogPeriod);
    if (server) server->Close();
    pub.reset();
    sub.reset();
    info.reset();
    context.reset();
  }
};

NetworkSubsystem::NetworkSubsystem(NetworkOptions options)
    : options_(std::move(options)), impl_(std::make_unique<Impl>()) {}

NetworkSubsystem::~NetworkSubsystem() {
  if (impl_ && impl_->thread.joinable()) {
    impl_->stop.store(true);
    impl_->bell->Ring();
    impl_->thread.join();
  }
}

void NetworkSubsystem::BeginPlay(world::Session& session) {
  impl_ = std::make_unique<Impl>();
  impl_->options = options_;
  impl_->model = session.engine().model();
  impl_->session = &session;
  impl_->tables = BuildTopicTables(session);
  impl_->free_bodies = FindFreeBodies(session, impl_->tables);
  for (std::size_t i = 0; i < impl_->tables.size(); ++i) {
    impl_->routes[impl_->tables[i].control_topic] = {i, Impl::Kind::kControl};
    impl_->routes[impl_->tables[i].set_gains_topic] = {i, Impl::Kind::kSetGains};
    impl_->info_messages.push_back(InfoJson(impl_->tables[i], cameras_));
  }
  impl_->frame = physics::StateFrame::SizedFor(impl_->model, session.engine().command_layout());
  if (!options_.full_state.empty()) {
    impl_->full_state = ParseObservationLevel(options_.full_state);
    if (!impl_->full_state) {
      spdlog::warn("network: full_state '{}' is not minimal, standard or full; not published",
                   options_.full_state);
    }
  }
  impl_->ring = session.engine().SubscribeEveryStep("network", options_.ring_capacity,
                                                    /*observed=*/true);
  impl_->ring->SetActive(false);  // on while the state socket has a subscriber (UpdateStreaming)
  session.engine().AddDoorbell(impl_->bell);
  if (!options_.rpc.empty()) {
    StepServerOptions so;
    so.endpoint = options_.rpc;
    so.mode = options_.step_mode;
    so.lease_timeout = options_.lease_timeout;
    so.limits.max_queued_steps = options_.max_queued_steps;
    so.shared_memory = options_.shared_memory;
    so.shm.folder = options_.shm_dir;
    if (!options_.files_dir.empty()) so.files_dir = options_.files_dir;
    so.inputs = world::SceneInputFiles(session.scene_config());
    so.scene_name = options_.scene_name;
    so.instance = options_.instance;
    so.server_session = options_.server_session;
    impl_->server = std::make_unique<StepServer>(
        session, impl_->tables, session.engine().SubscribeState("step_server", /*observed=*/true),
        so);
    impl_->server->SetRecorder(recorder_);
    impl_->server->SetCameras(cameras_);
    impl_->server->SetBatch(batch_);
    impl_->server->SetPlayback(playback_);
  }
  std::promise<Endpoints> ready;
  std::future<Endpoints> bound = ready.get_future();
  impl_->thread = std::thread([this, &ready] {
    pthread_setname_np(pthread_self(), "urlab-net");  // for top -H, perf, gdb
    impl_->Run(&ready);
  });
  bound_ = bound.get();
  if (options_.require_bind && !bound_.failures.empty()) {
    // Before the simulation starts: a client must never drive someone else's simulator.
    impl_->stop.store(true, std::memory_order_release);
    impl_->bell->Ring();
    impl_->thread.join();
    std::string what = bound_.failures.front();
    for (std::size_t i = 1; i < bound_.failures.size(); ++i) what += "; " + bound_.failures[i];
    throw Error(what +
                "; choose free ports (--ports auto, --port-base N, or the scene's network: "
                "section), or run without them (--allow-no-network)");
  }
  const auto shown = [](const std::string& e) { return e.empty() ? std::string("(none)") : e; };
  spdlog::info("network: state {} | control {} | info {} | rpc {}", shown(bound_.state),
               shown(bound_.control), shown(bound_.info), shown(bound_.rpc));
}

void NetworkSubsystem::EndPlay(world::Session&) {
  if (impl_->thread.joinable()) {
    impl_->stop.store(true, std::memory_order_release);
    impl_->bell->Ring();
    impl_->thread.join();
  }
  const NetworkCounters c = counters();
  spdlog::info(
      "network: {} step(s) published to state subscribers, {} control and {} gain message(s) "
      "applied, {} "
      "dropped, {} frame(s) the I/O thread missed",
      c.steps_published, c.controls_applied, c.gains_applied, c.total_drops(), c.frames_dropped);
}

std::vector<world::StatusLine> NetworkSubsystem::Status() const {
  const auto or_none = [](const std::string& e) {
    return e.empty() ? std::string("(not bound)") : e;
  };
  const NetworkCounters c = counters();
  return {{"state", or_none(bound_.state)},
          {"control", or_none(bound_.control)},
          {"info", or_none(bound_.info)},
          {"step server", or_none(bound_.rpc)},
          {"controls applied", std::to_string(c.controls_applied)},
          {"steps published", std::to_string(c.steps_published)},
          {"frames dropped", std::to_string(c.frames_dropped)},
          {"inbound dropped", std::to_string(c.total_drops())}};
}

NetworkCounters NetworkSubsystem::counters() const {
  NetworkCounters c;
  for (std::size_t i = 0; i < c.drops.size(); ++i) c.drops[i] = impl_->drops[i].load();
  c.controls_applied = impl_->controls_applied.load();
  c.gains_applied = impl_->gains_applied.load();
  c.steps_published = impl_->steps_published.load();
  c.info_published = impl_->info_published.load();
  c.state_messages = impl_->state_messages.load();
  c.frames_dropped = (impl_->ring ? impl_->ring->dropped() : 0) + impl_->frames_skipped.load();
  return c;
}

}  // namespace urlab::net
