#include "urlab/net/latency_bench.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <vector>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "net/bench_util.h"
#include "net/msgpack_codec.h"
#include "urlab/core/error.h"
#include "urlab/net/network.h"
#include "urlab/physics/model.h"
#include "urlab/wire/wire.h"
#include "urlab/world/manager.h"

namespace urlab::net {

namespace {

using bench::Format;
using bench::Median;
using Clock = std::chrono::steady_clock;

Percentiles Summarize(std::vector<double> us) {
  if (us.empty()) return {};
  std::sort(us.begin(), us.end());
  return {us[us.size() / 2], us[std::min(us.size() - 1, us.size() * 99 / 100)]};
}

// The value under `key` of a msgpack map object, nullptr when absent.
const msgpack::object* Field(const msgpack::object& map, std::string_view key) {
  if (map.type != msgpack::type::MAP) return nullptr;
  for (std::uint32_t i = 0; i < map.via.map.size; ++i) {
    const msgpack::object_kv& kv = map.via.map.ptr[i];
    if (kv.key.type == msgpack::type::STR &&
        std::string_view(kv.key.via.str.ptr, kv.key.via.str.size) == key) {
      return &kv.val;
    }
  }
  return nullptr;
}

// per_articulation[art].ctrl[0] of a state/full message, read without building a tree (the
// client must keep up with one message per physics step).
std::optional<double> FirstCtrl(const zmq::message_t& m, const std::string& art) {
  try {
    const msgpack::object_handle h = msgpack::unpack(static_cast<const char*>(m.data()), m.size());
    const msgpack::object* per = Field(h.get(), "per_articulation");
    const msgpack::object* a = per ? Field(*per, art) : nullptr;
    const msgpack::object* ctrl = a ? Field(*a, "ctrl") : nullptr;
    if (!ctrl || ctrl->type != msgpack::type::ARRAY || ctrl->via.array.size == 0) return {};
    return ctrl->via.array.ptr[0].as<double>();
  } catch (const std::exception&) {
    return {};
  }
}

constexpr int kPipelineWindow = 4;  // requests a pipelining client keeps in flight

double Micros(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

// Raw ZeroMQ floors: an echo thread answers each ping (same payload size as a control message).
// Kept alive through the whole run so raw and server samples can alternate. The echo side has
// its own ZeroMQ context (its own I/O thread), as a server in another process would, and as the
// network subsystem has: both ends sharing one I/O thread would be a shorter path than any
// client and server can have.
class RawPubSubEcho {
 public:
  explicit RawPubSubEcho(zmq::context_t& ctx)
      : echo_ctx_(1), out_(ctx, zmq::socket_type::pub), in_(ctx, zmq::socket_type::sub) {
    out_.bind("tcp://127.0.0.1:*");
    in_.bind("tcp://127.0.0.1:*");
    in_.set(zmq::sockopt::subscribe, "");
    in_.set(zmq::sockopt::rcvtimeo, 1000);
    const std::string to_echo = out_.get(zmq::sockopt::last_endpoint);
    const std::string from_echo = in_.get(zmq::sockopt::last_endpoint);
    echo_ = std::thread([this, to_echo, from_echo] {
      zmq::socket_t sub(echo_ctx_, zmq::socket_type::sub), pub(echo_ctx_, zmq::socket_type::pub);
      sub.set(zmq::sockopt::subscribe, "");
      sub.set(zmq::sockopt::rcvtimeo, 100);
      pub.set(zmq::sockopt::linger, 0);
      sub.connect(to_echo);
      pub.connect(from_echo);
      std::vector<zmq::message_t> parts;
      while (!stop_.load()) {
        parts.clear();
        if (zmq::recv_multipart(sub, std::back_inserter(parts))) zmq::send_multipart(pub, parts);
      }
    });
    // Until both subscriptions are joined, pings are lost: retry until they come back.
    for (int i = 0; i < 50; ++i) (void)Sample();
  }
  ~RawPubSubEcho() {
    stop_ = true;
    echo_.join();
  }
  // One round trip in microseconds, nothing when the ping was lost.
  std::optional<double> Sample() {
    const auto t0 = Clock::now();
    out_.send(zmq::buffer(std::string_view("ping")), zmq::send_flags::sndmore);
    out_.send(zmq::buffer(payload_), zmq::send_flags::none);
    std::vector<zmq::message_t> parts;
    if (!zmq::recv_multipart(in_, std::back_inserter(parts))) return std::nullopt;
    return Micros(Clock::now() - t0);
  }

 private:
  zmq::context_t echo_ctx_;  // first: outlives the sockets
  zmq::socket_t out_, in_;
  std::atomic<bool> stop_{false};
  std::thread echo_;
  const std::string payload_ = std::string(12, 'x');
};

class RawReqRepEcho {
 public:
  explicit RawReqRepEcho(zmq::context_t& ctx)
      : echo_ctx_(1), req_(ctx, zmq::socket_type::req), rep_(echo_ctx_, zmq::socket_type::rep) {
    rep_.set(zmq::sockopt::linger, 0);
    rep_.bind("tcp://127.0.0.1:*");
    rep_.set(zmq::sockopt::rcvtimeo, 100);
    echo_ = std::thread([this] {
      while (!stop_.load()) {
        zmq::message_t m;
        if (rep_.recv(m)) rep_.send(m, zmq::send_flags::none);
      }
    });
    req_.connect(rep_.get(zmq::sockopt::last_endpoint));
    payload_ = Json::to_msgpack(Json{{"op", "step"}});
    for (int i = 0; i < 50; ++i) (void)Sample();
  }
  ~RawReqRepEcho() {
    stop_ = true;
    echo_.join();
  }
  double Sample() {
    const auto t0 = Clock::now();
    req_.send(zmq::buffer(payload_));
    zmq::message_t m;
    (void)req_.recv(m);
    return Micros(Clock::now() - t0);
  }

 private:
  zmq::context_t echo_ctx_;  // first: outlives the sockets
  zmq::socket_t req_, rep_;  // rep_ is used by the echo thread only (after construction)
  std::atomic<bool> stop_{false};
  std::thread echo_;
  std::vector<std::uint8_t> payload_;
};

// Steps per second of `steps` bare mj_step calls on (m, d), continuing from d's state.
double BareRate(const mjModel* m, mjData* d, int steps) {
  const auto t0 = Clock::now();
  for (int i = 0; i < steps; ++i) mj_step(m, d);
  return steps / std::chrono::duration<double>(Clock::now() - t0).count();
}

class RpcClient {
 public:
  RpcClient(zmq::context_t& ctx, const std::string& endpoint)
      : socket_(ctx, zmq::socket_type::req) {
    socket_.set(zmq::sockopt::rcvtimeo, 10000);
    socket_.connect(endpoint);
  }
  // A request whose whole reply is wanted (decoded into a tree).
  Json Call(Json request) {
    const msgpack::object_handle h = Exchange(std::move(request));
    std::string why;
    Json r = DecodeMsgpack(reply_.data(), reply_.size(), &why).value_or(Json());
    if (r.contains("session_id")) session_ = r["session_id"];
    return r;
  }
  // A step in the throughput loop: the reply is only checked (a learning loop reads what it
  // needs; decoding every number into a tree would measure this client, not the server).
  void Step(const Json& request) { (void)Exchange(request); }
  const std::string& session() const { return session_; }

 private:
  msgpack::object_handle Exchange(Json request) {
    if (!session_.empty()) request["session_id"] = session_;
    writer_.Clear();
    writer_.Value(request);
    socket_.send(zmq::buffer(writer_.data(), writer_.size()));
    if (!socket_.recv(reply_)) throw Error("bench latency: the step server did not answer");
    msgpack::object_handle h =
        msgpack::unpack(static_cast<const char*>(reply_.data()), reply_.size());
    const msgpack::object* op = Field(h.get(), "op");
    if (!op || op->type != msgpack::type::STR ||
        std::string_view(op->via.str.ptr, op->via.str.size) == "error") {
      const msgpack::object* m = Field(h.get(), "message");
      throw Error("bench latency: the step server refused a request" +
                  (m && m->type == msgpack::type::STR
                       ? ": " + std::string(m->via.str.ptr, m->via.str.size)
                       : std::string()));
    }
    return h;
  }

  zmq::socket_t socket_;
  std::string session_;
  MsgpackWriter writer_;
  zmq::message_t reply_;
};

// A DEALER client keeping `window` step requests in flight (of the same session as a REQ
// client): measures what the server can process, not one round trip per step.
double PipelinedRate(zmq::context_t& ctx, const std::string& endpoint, const std::string& session,
                     int n, int requests, int window) {
  zmq::socket_t dealer(ctx, zmq::socket_type::dealer);
  dealer.set(zmq::sockopt::rcvtimeo, 10000);
  dealer.set(zmq::sockopt::linger, 0);
  dealer.connect(endpoint);
  MsgpackWriter writer;
  writer.Value(Json{{"op", "step"}, {"n_steps", n}, {"session_id", session}});
  const auto t0 = Clock::now();
  int sent = 0, received = 0;
  zmq::message_t reply;
  while (received < requests) {
    while (sent < requests && sent - received < window) {
      dealer.send(zmq::buffer(writer.data(), writer.size()));
      ++sent;
    }
    if (!dealer.recv(reply)) throw Error("bench latency: the step server did not answer");
    const msgpack::object_handle h =
        msgpack::unpack(static_cast<const char*>(reply.data()), reply.size());
    const msgpack::object* op = Field(h.get(), "op");
    if (!op || op->type != msgpack::type::STR ||
        std::string_view(op->via.str.ptr, op->via.str.size) != "step_ok") {
      throw Error("bench latency: a pipelined step was refused");
    }
    ++received;
  }
  return requests * n / std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

LatencyBenchResult RunLatencyBench(world::SceneConfig scene, const LatencyBenchOptions& options) {
  const auto report = [&](const std::string& line) {
    if (options.report) options.report(line);
  };
  if (scene.articulations.empty()) throw Error("bench latency: the scene has no articulation");
  scene.articulations.resize(1);
  world::ArticulationConfig& art = scene.articulations.front();
  art.controller = world::ControllerConfig{};  // passthrough: the state shows the control as sent
  art.hold_keyframe = false;
  art.control_source = control::ControlSource::kNetwork;
  scene.save_debug_xml.clear();

  LatencyBenchResult r;
  zmq::context_t ctx(1);
  RawPubSubEcho raw_pubsub(ctx);
  RawReqRepEcho raw_reqrep(ctx);

  NetworkOptions no;
  no.state = no.control = no.info = no.rpc = "tcp://127.0.0.1:*";
  no.full_state = "standard";
  world::ManagerOptions mo;
  mo.as_fast_as_possible = true;
  world::Manager manager(mo);
  auto& net =
      static_cast<NetworkSubsystem&>(manager.AddSubsystem(std::make_unique<NetworkSubsystem>(no)));
  manager.BeginPlay(scene);
  physics::PhysicsEngine& engine = manager.session().engine();
  const world::Articulation& a = manager.session().articulations().front();
  const mjModel* m = engine.model();
  const physics::Model bare_model = engine.CopyModel();  // with the model's extensions
  const physics::DataPtr bare_data = physics::MakeData(bare_model.get());
  mj_forward(bare_model.get(), bare_data.get());
  if (a.control->num_actuators() == 0)
    throw Error("bench latency: '" + a.name() + "' has no actuator");
  const int actuator = a.control->actuator_ids().front();
  double lo = -1, hi = 1;
  if (m->actuator_ctrllimited[actuator]) {
    lo = m->actuator_ctrlrange[2 * actuator];
    hi = m->actuator_ctrlrange[2 * actuator + 1];
  }
  // Distinct values inside the control range, so each one identifies its message.
  const auto value = [&](int i) { return lo + (hi - lo) * (0.25 + 0.5 * ((i % 997) / 997.0)); };
  report(Format("scene %s: articulation '%s', %d actuator(s), timestep %.4f s", scene.path.c_str(),
                a.name().c_str(), a.control->num_actuators(), engine.timestep()));
  report(Format("%d rounds; raw and URLab samples alternate round by round (shared machine)",
                options.rounds));
  const int per_round = std::max(1, options.samples / options.rounds);
  const auto set_paused = [&](bool paused) {
    (void)engine.WaitForCommand(engine.Submit(physics::cmd::SetPaused{paused}),
                                std::chrono::seconds(5));
  };

  // Streaming: control topic in, state/full out. The engine is paused while the raw floor is
  // sampled, so that floor is not measured against our own busy physics thread.
  {
    zmq::socket_t control(ctx, zmq::socket_type::pub), state(ctx, zmq::socket_type::sub);
    control.connect(net.endpoints().control);
    state.set(zmq::sockopt::subscribe, std::string(wire::kFullStateTopic));
    state.set(zmq::sockopt::rcvtimeo, 2000);
    state.connect(net.endpoints().state);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // subscriptions join
    const std::string topic = wire::ControlTopic(a.name());
    std::vector<double> raw, ours;
    int sent = 0;
    for (int round = 0; round < options.rounds; ++round) {
      set_paused(true);
      for (int i = 0; i < per_round; ++i) {
        if (const auto us = raw_pubsub.Sample()) raw.push_back(*us);
      }
      set_paused(false);
      for (int i = 0; i < per_round + 5; ++i, ++sent) {
        const float v = static_cast<float>(value(sent));
        std::string payload;
        const std::pair<std::int32_t, float> one[] = {{actuator, v}};
        wire::AppendControl(&payload, one);
        const auto t0 = Clock::now();
        control.send(zmq::buffer(topic), zmq::send_flags::sndmore);
        control.send(zmq::buffer(payload), zmq::send_flags::none);
        bool seen = false;
        while (!seen && Clock::now() - t0 < std::chrono::seconds(2)) {
          std::vector<zmq::message_t> parts;
          if (!zmq::recv_multipart(state, std::back_inserter(parts)) || parts.size() != 2) break;
          const std::optional<double> c = FirstCtrl(parts[1], a.name());
          seen = c && static_cast<float>(*c) == v;
        }
        if (seen && i >= 5) ours.push_back(Micros(Clock::now() - t0));  // 5 to settle
      }
    }
    r.raw_pubsub = Summarize(raw);
    r.streaming = Summarize(ours);
    report(Format("streaming control -> state/full: %zu round trips", ours.size()));
  }

  // Lockstep: direct mode, one step per request, each reply checked for its own control.
  RpcClient client(ctx, net.endpoints().rpc);
  client.Call(Json{{"op", "hello"}, {"observations", "standard"}});
  client.Call(Json{{"op", "set_mode"}, {"mode", "direct"}});
  {
    std::vector<double> raw, ours;
    const std::size_t nu = static_cast<std::size_t>(a.control->num_actuators());
    int sent = 0;
    for (int round = 0; round < options.rounds; ++round) {
      for (int i = 0; i < per_round; ++i) raw.push_back(raw_reqrep.Sample());
      for (int i = 0; i < per_round + 5; ++i, ++sent) {
        const double v = value(sent);
        const auto t0 = Clock::now();
        const Json reply = client.Call(
            Json{{"op", "step"},
                 {"n_steps", 1},
                 {"per_articulation", {{a.name(), {{"ctrl", std::vector<double>(nu, v)}}}}}});
        const auto t1 = Clock::now();
        if (reply["per_articulation"][a.name()]["ctrl"][0].get<double>() != v) {
          throw Error("bench latency: a lockstep reply does not show its own control");
        }
        if (i >= 5) ours.push_back(Micros(t1 - t0));
      }
    }
    r.raw_reqrep = Summarize(raw);
    r.lockstep = Summarize(ours);
  }
  // Throughput: bare mj_step, then n=1, then n=10, round by round; each ratio is taken within
  // its round and the median ratio reported.
  {
    std::vector<double> bare, n1, n10, ratio1, ratio10, piped1, piped10;
    const int steps = std::max(10, options.throughput_steps / options.rounds);
    for (int round = 0; round < options.rounds; ++round) {
      bare.push_back(BareRate(bare_model.get(), bare_data.get(), steps));
      for (const int n : {1, 10}) {
        const int requests = std::max(1, steps / n);
        const Json step{{"op", "step"}, {"n_steps", n}};
        const auto t0 = Clock::now();
        for (int i = 0; i < requests; ++i) client.Step(step);
        const double rate = requests * n / std::chrono::duration<double>(Clock::now() - t0).count();
        (n == 1 ? n1 : n10).push_back(rate);
        (n == 1 ? ratio1 : ratio10).push_back(rate / bare.back());
        const double piped =
            PipelinedRate(ctx, net.endpoints().rpc, client.session(), n, requests, kPipelineWindow);
        (n == 1 ? piped1 : piped10).push_back(piped / bare.back());
      }
    }
    r.pipelined_ratio_n1 = Median(piped1);
    r.pipelined_ratio_n10 = Median(piped10);
    r.bare_rate = Median(bare);
    r.lockstep_rate_n1 = Median(n1);
    r.lockstep_rate_n10 = Median(n10);
    r.throughput_ratio_n1 = Median(ratio1);
    r.throughput_ratio_n10 = Median(ratio10);
    const double step_us = 1e6 / r.bare_rate;
    const auto ceiling = [&](int n) { return n * step_us / (n * step_us + r.raw_reqrep.p50_us); };
    r.ceiling_n1 = ceiling(1);
    r.ceiling_n10 = ceiling(10);
  }
  manager.EndPlay();

  report(Format("raw PUB/SUB ping-pong        p50 %8.1f us  p99 %8.1f us", r.raw_pubsub.p50_us,
                r.raw_pubsub.p99_us));
  report(Format("streaming control->state     p50 %8.1f us  p99 %8.1f us  (%.2fx raw)",
                r.streaming.p50_us, r.streaming.p99_us, r.streaming.p50_us / r.raw_pubsub.p50_us));
  report(Format("raw REQ/REP ping-pong        p50 %8.1f us  p99 %8.1f us", r.raw_reqrep.p50_us,
                r.raw_reqrep.p99_us));
  report(Format("lockstep step n=1            p50 %8.1f us  p99 %8.1f us  (%.2fx raw)",
                r.lockstep.p50_us, r.lockstep.p99_us, r.lockstep.p50_us / r.raw_reqrep.p50_us));
  report(Format("bare mj_step                 %9.0f steps/s (median of rounds)", r.bare_rate));
  report(
      Format("lockstep throughput n=1      %9.0f steps/s (median ratio %.3f of bare; the raw "
             "round trip p50 added to each step would give %.3f)",
             r.lockstep_rate_n1, r.throughput_ratio_n1, r.ceiling_n1));
  report(
      Format("lockstep throughput n=10     %9.0f steps/s (median ratio %.3f of bare; the raw "
             "round trip p50 added to each step would give %.3f)",
             r.lockstep_rate_n10, r.throughput_ratio_n10, r.ceiling_n10));
  report(
      Format("server capacity (%d step requests in flight): n=1 ratio %.3f, n=10 ratio %.3f "
             "of bare",
             kPipelineWindow, r.pipelined_ratio_n1, r.pipelined_ratio_n10));
  return r;
}

}  // namespace urlab::net
