#include "urlab/net/latency_bench.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "urlab/core/error.h"
#include "urlab/net/network.h"
#include "urlab/net/wire.h"
#include "urlab/physics/model.h"
#include "urlab/world/manager.h"

namespace urlab::net {

namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

Percentiles Summarize(std::vector<double> us) {
  if (us.empty()) return {};
  std::sort(us.begin(), us.end());
  return {us[us.size() / 2], us[std::min(us.size() - 1, us.size() * 99 / 100)]};
}

double Micros(Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }

template <typename... Args>
std::string Format(const char* fmt, Args... args) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, args...);
  return buf;
}

// Raw ZeroMQ floors: an echo thread answers each ping; same payload size as a control message.
Percentiles RawPubSub(zmq::context_t& ctx, int samples) {
  zmq::socket_t out(ctx, zmq::socket_type::pub), in(ctx, zmq::socket_type::sub);
  out.bind("tcp://127.0.0.1:*");
  in.bind("tcp://127.0.0.1:*");
  in.set(zmq::sockopt::subscribe, "");
  const std::string to_echo = out.get(zmq::sockopt::last_endpoint);
  const std::string from_echo = in.get(zmq::sockopt::last_endpoint);
  std::atomic<bool> stop{false};
  std::thread echo([&] {
    zmq::socket_t sub(ctx, zmq::socket_type::sub), pub(ctx, zmq::socket_type::pub);
    sub.set(zmq::sockopt::subscribe, "");
    sub.set(zmq::sockopt::rcvtimeo, 100);
    sub.connect(to_echo);
    pub.connect(from_echo);
    std::vector<zmq::message_t> parts;
    while (!stop.load()) {
      parts.clear();
      if (zmq::recv_multipart(sub, std::back_inserter(parts))) {
        zmq::send_multipart(pub, parts);
      }
    }
  });
  in.set(zmq::sockopt::rcvtimeo, 1000);
  std::vector<double> us;
  const std::string payload(12, 'x');
  // Until both subscriptions are joined, pings are lost: retry until one comes back.
  for (int i = 0; i < samples + 50; ++i) {
    const auto t0 = Clock::now();
    out.send(zmq::buffer(std::string_view("ping")), zmq::send_flags::sndmore);
    out.send(zmq::buffer(payload), zmq::send_flags::none);
    std::vector<zmq::message_t> parts;
    if (!zmq::recv_multipart(in, std::back_inserter(parts))) continue;
    if (i >= 50) us.push_back(Micros(Clock::now() - t0));
  }
  stop = true;
  echo.join();
  return Summarize(us);
}

Percentiles RawReqRep(zmq::context_t& ctx, int samples) {
  zmq::socket_t req(ctx, zmq::socket_type::req);
  zmq::socket_t rep(ctx, zmq::socket_type::rep);
  rep.bind("tcp://127.0.0.1:*");
  const std::string endpoint = rep.get(zmq::sockopt::last_endpoint);
  std::thread echo([&] {
    for (int i = 0; i < samples + 50; ++i) {
      zmq::message_t m;
      if (!rep.recv(m)) return;
      rep.send(m, zmq::send_flags::none);
    }
  });
  req.connect(endpoint);
  std::vector<double> us;
  const std::vector<std::uint8_t> payload = Json::to_msgpack(Json{{"op", "step"}});
  for (int i = 0; i < samples + 50; ++i) {
    const auto t0 = Clock::now();
    req.send(zmq::buffer(payload));
    zmq::message_t m;
    (void)req.recv(m);
    if (i >= 50) us.push_back(Micros(Clock::now() - t0));
  }
  echo.join();
  return Summarize(us);
}

double BareRate(const mjModel* model, int steps) {
  physics::ModelPtr m(mj_copyModel(nullptr, model));
  physics::DataPtr d = physics::MakeData(m.get());
  mj_forward(m.get(), d.get());
  const auto t0 = Clock::now();
  for (int i = 0; i < steps; ++i) mj_step(m.get(), d.get());
  return steps / std::chrono::duration<double>(Clock::now() - t0).count();
}

class RpcClient {
 public:
  RpcClient(zmq::context_t& ctx, const std::string& endpoint)
      : socket_(ctx, zmq::socket_type::req) {
    socket_.set(zmq::sockopt::rcvtimeo, 10000);
    socket_.connect(endpoint);
  }
  Json Call(Json request) {
    if (!session_.empty()) request["session_id"] = session_;
    const std::vector<std::uint8_t> bytes = Json::to_msgpack(request);
    socket_.send(zmq::buffer(bytes));
    zmq::message_t reply;
    if (!socket_.recv(reply)) throw Error("bench latency: the step server did not answer");
    const auto* p = static_cast<const std::uint8_t*>(reply.data());
    Json r = Json::from_msgpack(p, p + reply.size());
    if (r["op"] == "error") throw Error("bench latency: " + r.value("message", std::string()));
    if (r.contains("session_id")) session_ = r["session_id"];
    return r;
  }

 private:
  zmq::socket_t socket_;
  std::string session_;
};

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
  r.raw_pubsub = RawPubSub(ctx, options.samples);
  r.raw_reqrep = RawReqRep(ctx, options.samples);

  NetworkOptions no;
  no.state = no.control = no.info = no.rpc = "tcp://127.0.0.1:*";
  no.full_state = "standard";
  world::ManagerOptions mo;
  mo.as_fast_as_possible = true;
  world::Manager manager(mo);
  auto& net =
      static_cast<NetworkSubsystem&>(manager.AddSubsystem(std::make_unique<NetworkSubsystem>(no)));
  manager.BeginPlay(scene);
  const world::Articulation& a = manager.session().articulations().front();
  const mjModel* m = manager.session().engine().model();
  const physics::ModelPtr bare_model(mj_copyModel(nullptr, m));
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
                a.name().c_str(), a.control->num_actuators(),
                manager.session().engine().timestep()));

  // Streaming: control topic in, state/full out.
  {
    zmq::socket_t control(ctx, zmq::socket_type::pub), state(ctx, zmq::socket_type::sub);
    control.connect(net.endpoints().control);
    state.set(zmq::sockopt::subscribe, std::string(wire::kFullStateTopic));
    state.set(zmq::sockopt::rcvtimeo, 2000);
    state.connect(net.endpoints().state);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // subscriptions join
    std::vector<double> us;
    for (int i = 0; i < options.samples + 20; ++i) {
      const float v = static_cast<float>(value(i));
      std::string payload;
      const std::pair<std::int32_t, float> one[] = {{actuator, v}};
      wire::AppendControl(&payload, one);
      const std::string topic = wire::ControlTopic(a.name());
      const auto t0 = Clock::now();
      control.send(zmq::buffer(topic), zmq::send_flags::sndmore);
      control.send(zmq::buffer(payload), zmq::send_flags::none);
      bool seen = false;
      while (!seen && Clock::now() - t0 < std::chrono::seconds(2)) {
        std::vector<zmq::message_t> parts;
        if (!zmq::recv_multipart(state, std::back_inserter(parts)) || parts.size() != 2) break;
        const auto* p = static_cast<const std::uint8_t*>(parts[1].data());
        const Json obs = Json::from_msgpack(p, p + parts[1].size(), true, false);
        if (obs.is_discarded()) continue;
        const double c = obs["per_articulation"][a.name()]["ctrl"][0];
        seen = static_cast<float>(c) == v;
      }
      if (seen && i >= 20) us.push_back(Micros(Clock::now() - t0));
    }
    r.streaming = Summarize(us);
    report(Format("streaming control -> state/full: %zu round trips", us.size()));
  }

  // Lockstep: direct mode, one step per request.
  RpcClient client(ctx, net.endpoints().rpc);
  client.Call(Json{{"op", "hello"}, {"observations", "standard"}});
  client.Call(Json{{"op", "set_mode"}, {"mode", "direct"}});
  {
    std::vector<double> us;
    const std::size_t nu = static_cast<std::size_t>(a.control->num_actuators());
    for (int i = 0; i < options.samples + 20; ++i) {
      const double v = value(i);
      const auto t0 = Clock::now();
      const Json reply = client.Call(
          Json{{"op", "step"},
               {"n_steps", 1},
               {"per_articulation", {{a.name(), {{"ctrl", std::vector<double>(nu, v)}}}}}});
      const auto t1 = Clock::now();
      if (reply["per_articulation"][a.name()]["ctrl"][0].get<double>() != v) {
        throw Error("bench latency: a lockstep reply does not show its own control");
      }
      if (i >= 20) us.push_back(Micros(t1 - t0));
    }
    r.lockstep = Summarize(us);
  }
  for (const int n : {1, 10}) {
    const int requests = std::max(1, options.throughput_steps / n);
    const auto t0 = Clock::now();
    for (int i = 0; i < requests; ++i) client.Call(Json{{"op", "step"}, {"n_steps", n}});
    const double rate = requests * n / std::chrono::duration<double>(Clock::now() - t0).count();
    (n == 1 ? r.lockstep_rate_n1 : r.lockstep_rate_n10) = rate;
  }
  manager.EndPlay();
  r.bare_rate = BareRate(bare_model.get(), options.throughput_steps * 2);

  report(Format("raw PUB/SUB ping-pong        p50 %8.1f us  p99 %8.1f us", r.raw_pubsub.p50_us,
                r.raw_pubsub.p99_us));
  report(Format("streaming control->state     p50 %8.1f us  p99 %8.1f us  (%.2fx raw)",
                r.streaming.p50_us, r.streaming.p99_us, r.streaming.p50_us / r.raw_pubsub.p50_us));
  report(Format("raw REQ/REP ping-pong        p50 %8.1f us  p99 %8.1f us", r.raw_reqrep.p50_us,
                r.raw_reqrep.p99_us));
  report(Format("lockstep step n=1            p50 %8.1f us  p99 %8.1f us  (%.2fx raw)",
                r.lockstep.p50_us, r.lockstep.p99_us, r.lockstep.p50_us / r.raw_reqrep.p50_us));
  report(Format("lockstep throughput n=1  %9.0f steps/s (%.3f of bare %.0f)", r.lockstep_rate_n1,
                r.lockstep_rate_n1 / r.bare_rate, r.bare_rate));
  report(Format("lockstep throughput n=10 %9.0f steps/s (%.3f of bare)", r.lockstep_rate_n10,
                r.lockstep_rate_n10 / r.bare_rate));
  return r;
}

}  // namespace urlab::net
