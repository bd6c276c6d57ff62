#include "urlab/client/client.h"

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <thread>
#include <zmq.hpp>
#include <zmq_addon.hpp>

#include "wire/shm_channel.h"
#include "wire/shm_wait.h"

namespace urlab::client {

namespace {

using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;

zmq::socket_t Socket(zmq::context_t& ctx, zmq::socket_type type) {
  zmq::socket_t s(ctx, type);
  s.set(zmq::sockopt::linger, 0);
  return s;
}

std::vector<double> Doubles(const Json& v) {
  if (v.is_binary()) {
    const auto& b = v.get_binary();
    std::vector<double> out(b.size() / sizeof(double));
    std::memcpy(out.data(), b.data(), out.size() * sizeof(double));
    return out;
  }
  return v.is_array() ? v.get<std::vector<double>>() : std::vector<double>{};
}

Observation ToObservation(const Json& r) {
  Observation o;
  o.time = r.value("time", 0.0);
  o.step = r.value("step", std::uint64_t{0});
  for (const auto& [name, a] : r["per_articulation"].items()) {
    ArticulationObservation& out = o.per_articulation[name];
    out.qpos = Doubles(a["qpos"]);
    out.qvel = Doubles(a["qvel"]);
    if (a.contains("ctrl")) out.ctrl = Doubles(a["ctrl"]);
    if (a.contains("act")) out.act = Doubles(a["act"]);
    if (a.contains("sensors")) {
      for (const auto& [s, v] : a["sensors"].items()) out.sensors[s] = Doubles(v);
    }
  }
  return o;
}

}  // namespace

Endpoints Endpoints::OnHost(const std::string& host) {
  Endpoints e;
  e.state = "tcp://" + host + ":5555";
  e.control = "tcp://" + host + ":5556";
  e.info = "tcp://" + host + ":5557";
  e.rpc = "tcp://" + host + ":5559";
  return e;
}

int Robot::ActuatorId(std::string_view n) const {
  for (std::size_t i = 0; i < actuator_names.size(); ++i) {
    // The short name, or the full "{robot}_{actuator}" name.
    const std::string& short_name = actuator_names[i];
    if (short_name == n || (n.size() == name.size() + 1 + short_name.size() &&
                            n.starts_with(name + "_") && n.ends_with(short_name))) {
      return actuator_ids[i];
    }
  }
  throw std::out_of_range(name + ": no actuator '" + std::string(n) + "'");
}

// ---------------------------------------------------------------------------------------------
// StreamClient

struct StreamClient::Impl {
  zmq::context_t ctx{1};
  zmq::socket_t state = Socket(ctx, zmq::socket_type::sub);
  zmq::socket_t info = Socket(ctx, zmq::socket_type::sub);
  zmq::socket_t control = Socket(ctx, zmq::socket_type::pub);
  std::map<std::string, Robot> robots;
  std::map<std::string, wire::JointMessage> joints;     // "robot/joint"
  std::map<std::string, wire::BaseStateMessage> bases;  // "robot/joint"
  std::map<std::string, std::vector<float>> sensors;    // "robot/sensor"
};

StreamClient::StreamClient(Endpoints e) : impl_(std::make_unique<Impl>()) {
  impl_->state.set(zmq::sockopt::subscribe, "");
  impl_->state.connect(e.state);
  impl_->info.set(zmq::sockopt::subscribe, "");
  impl_->info.connect(e.info);
  impl_->control.connect(e.control);
}

StreamClient::~StreamClient() = default;

const std::map<std::string, Robot>& StreamClient::robots() const { return impl_->robots; }

const std::map<std::string, Robot>& StreamClient::Discover(std::chrono::milliseconds timeout,
                                                           const std::vector<std::string>& expect) {
  const auto end = Clock::now() + timeout;
  std::optional<Clock::time_point> last_new;
  const auto complete = [&] {
    if (expect.empty()) return last_new && Clock::now() - *last_new > std::chrono::seconds(1);
    for (const std::string& r : expect) {
      if (!impl_->robots.count(r)) return false;
    }
    return true;
  };
  while (!complete() && Clock::now() < end) {
    zmq::pollitem_t item{static_cast<void*>(impl_->info), 0, ZMQ_POLLIN, 0};
    zmq::poll(&item, 1, std::chrono::milliseconds(50));
    zmq::message_t m;
    while (impl_->info.recv(m, zmq::recv_flags::dontwait)) {
      const Json j = Json::parse(m.to_string_view(), nullptr, false);
      if (j.is_discarded() || j.value("type", "") != "actuator_list") continue;
      Robot r;
      r.name = j["robot"];
      r.actuator_names = j["names"].get<std::vector<std::string>>();
      r.actuator_ids = j["ids"].get<std::vector<int>>();
      r.mins = j["mins"].get<std::vector<double>>();
      r.maxs = j["maxs"].get<std::vector<double>>();
      if (impl_->robots.emplace(r.name, r).second) last_new = Clock::now();
    }
  }
  if (!complete() && (impl_->robots.empty() || !expect.empty())) {
    throw std::runtime_error("urlab client: no discovery within the timeout");
  }
  return impl_->robots;
}

int StreamClient::Poll(std::chrono::milliseconds timeout) {
  if (timeout.count() > 0) {
    zmq::pollitem_t item{static_cast<void*>(impl_->state), 0, ZMQ_POLLIN, 0};
    zmq::poll(&item, 1, timeout);
  }
  int n = 0;
  std::vector<zmq::message_t> parts;
  while (true) {
    parts.clear();
    if (!zmq::recv_multipart(impl_->state, std::back_inserter(parts), zmq::recv_flags::dontwait)) {
      return n;
    }
    if (parts.size() != 2) continue;
    ++n;
    const std::string topic = parts[0].to_string();
    const std::string_view payload = parts[1].to_string_view();
    const auto a = topic.find('/');
    const auto b = topic.find('/', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string kind = topic.substr(a + 1, b - a - 1);
    const std::string key = topic.substr(0, a) + "/" + topic.substr(b + 1);
    if (kind == "joint") {
      if (auto j = wire::DecodeJoint(payload)) impl_->joints[key] = *j;
    } else if (kind == "base_state") {
      if (auto s = wire::DecodeBaseState(payload)) impl_->bases[key] = *s;
    } else if (kind == "sensor") {
      if (auto s = wire::DecodeSensor(payload)) impl_->sensors[key] = s->values;
    }
  }
}

std::optional<wire::JointMessage> StreamClient::Joint(const std::string& robot,
                                                      const std::string& joint) const {
  const auto it = impl_->joints.find(robot + "/" + joint);
  return it == impl_->joints.end() ? std::nullopt : std::optional(it->second);
}

std::optional<wire::BaseStateMessage> StreamClient::Base(const std::string& robot,
                                                         const std::string& joint) const {
  const auto it = impl_->bases.find(robot + "/" + joint);
  return it == impl_->bases.end() ? std::nullopt : std::optional(it->second);
}

std::optional<std::vector<float>> StreamClient::Sensor(const std::string& robot,
                                                       const std::string& sensor) const {
  const auto it = impl_->sensors.find(robot + "/" + sensor);
  return it == impl_->sensors.end() ? std::nullopt : std::optional(it->second);
}

void StreamClient::SendControl(const std::string& robot,
                               const std::map<std::string, double>& targets) {
  const auto it = impl_->robots.find(robot);
  if (it == impl_->robots.end()) {
    throw std::out_of_range("urlab client: no robot '" + robot + "' (call Discover first)");
  }
  std::vector<std::pair<std::int32_t, float>> values;
  for (const auto& [name, v] : targets) {
    values.emplace_back(it->second.ActuatorId(name), static_cast<float>(v));
  }
  std::string payload;
  wire::AppendControl(&payload, values);
  const std::string topic = wire::ControlTopic(robot);
  impl_->control.send(zmq::buffer(topic), zmq::send_flags::sndmore);
  impl_->control.send(zmq::buffer(payload), zmq::send_flags::none);
}

void StreamClient::SetGains(const std::string& robot, const std::string& json) {
  const std::string topic = wire::SetGainsTopic(robot);
  impl_->control.send(zmq::buffer(topic), zmq::send_flags::sndmore);
  impl_->control.send(zmq::buffer(json), zmq::send_flags::none);
}

// ---------------------------------------------------------------------------------------------
// StepClient

struct StepClient::Impl {
  zmq::context_t ctx{1};
  zmq::socket_t socket = Socket(ctx, zmq::socket_type::req);
  std::string session;
  std::string hello;
  std::uint64_t seq = 0;
  std::chrono::milliseconds timeout{10000};
  std::optional<wire::ShmChannel> channel;  // after hello, when the server offered one
  wire::ShmRoundTrips round_trips;          // what the next round trip is expected to take

  Json Request(Json request) {
    request["seq"] = ++seq;
    if (!session.empty()) request["session_id"] = session;
    const std::vector<std::uint8_t> bytes = Json::to_msgpack(request);
    if (channel && request.value("op", "") != "hello") {
      // Spin about as long as the server is expected to take (the channel's wait policy), then
      // sleep on the reply word.
      const int steps = wire::RequestSteps(request.value("op", ""), request.value("n_steps", 1));
      const auto t0 = Clock::now();
      channel->SendRequest(bytes);
      std::span<const std::uint8_t> reply;
      try {
        reply = channel->WaitReply(timeout,
                                   wire::SpinBudget(round_trips.Expected(steps), wire::SpareCore));
      } catch (const wire::ShmError& e) {
        throw std::runtime_error(std::string("urlab client: ") + e.what());
      }
      round_trips.Took(steps, Clock::now() - t0);
      return Decode(reply.data(), reply.size());
    }
    socket.send(zmq::buffer(bytes));
    zmq::message_t reply;
    if (!socket.recv(reply)) {
      throw std::runtime_error("urlab client: no reply to '" + request.value("op", "") + "'");
    }
    return Decode(static_cast<const std::uint8_t*>(reply.data()), reply.size());
  }

  static Json Decode(const std::uint8_t* p, std::size_t size) {
    Json r = Json::from_msgpack(p, p + size, true, false);
    if (r.is_discarded()) throw std::runtime_error("urlab client: a reply that is not msgpack");
    if (r.value("op", "") == "error") {
      throw StepError(r.value("code", "error"), r.value("message", std::string()));
    }
    return r;
  }
};

StepClient::StepClient(const std::string& endpoint, const std::string& observations,
                       std::chrono::milliseconds timeout, bool shared_memory)
    : impl_(std::make_unique<Impl>()) {
  impl_->timeout = timeout;
  impl_->socket.set(zmq::sockopt::rcvtimeo, static_cast<int>(timeout.count()));
  impl_->socket.connect(endpoint);
  Json hello{{"op", "hello"}, {"observations", observations}};
  if (shared_memory) hello["shm"] = true;
  Json h = impl_->Request(std::move(hello));
  impl_->session = h["session_id"];
  if (const auto it = h.find("shm"); it != h.end() && it->is_object()) {
    try {
      impl_->channel.emplace(wire::ShmChannel::Attach(it->at("path").get<std::string>(),
                                                      it->at("generation").get<std::uint64_t>()));
    } catch (const std::exception&) {
      // Stays on ZeroMQ (transport() says so).
    }
  }
  h.erase("mjb");
  impl_->hello = h.dump();
}

StepClient::~StepClient() {
  try {
    impl_->Request(Json{{"op", "bye"}});
  } catch (const std::exception&) {  // the server may be gone already
  }
}

const std::string& StepClient::session_id() const { return impl_->session; }
std::string StepClient::transport() const { return impl_->channel ? "shm" : "zmq"; }
const std::string& StepClient::hello_json() const { return impl_->hello; }

std::string StepClient::Call(const std::string& op, const std::string& fields) {
  Json request = Json::parse(fields, nullptr, false);
  if (!request.is_object())
    throw std::invalid_argument("urlab client: fields must be a JSON object");
  request["op"] = op;
  Json r = impl_->Request(std::move(request));
  return r.dump(-1, ' ', false, Json::error_handler_t::replace);
}

void StepClient::SetMode(const std::string& mode) {
  impl_->Request(Json{{"op", "set_mode"}, {"mode", mode}});
}

Observation StepClient::Step(int n_steps,
                             const std::map<std::string, std::vector<double>>& controls) {
  Json request{{"op", "step"}, {"n_steps", n_steps}};
  for (const auto& [art, ctrl] : controls) request["per_articulation"][art]["ctrl"] = ctrl;
  return ToObservation(impl_->Request(std::move(request)));
}

Observation StepClient::Reset(const std::string& keyframe) {
  Json request{{"op", "reset"}};
  if (!keyframe.empty()) request["keyframe_name"] = keyframe;
  return ToObservation(impl_->Request(std::move(request)));
}

Observation StepClient::Puppet(const std::map<std::string, PuppetState>& per_articulation,
                               std::optional<double> time) {
  Json request{{"op", "step"}};
  for (const auto& [art, state] : per_articulation) {
    Json entry = Json::object();
    if (!state.qpos.empty()) entry["qpos"] = state.qpos;
    if (!state.qvel.empty()) entry["qvel"] = state.qvel;
    if (!state.ctrl.empty()) entry["ctrl"] = state.ctrl;
    request["per_articulation"][art] = std::move(entry);
  }
  if (time) request["time"] = *time;
  return ToObservation(impl_->Request(std::move(request)));
}

std::vector<Contact> StepClient::Contacts(int max_contacts, bool* truncated) {
  const Json reply = impl_->Request(Json{{"op", "get_contacts"}, {"max_contacts", max_contacts}});
  std::vector<Contact> out;
  for (const Json& c : reply.at("contacts")) {
    Contact k;
    k.geom1 = c.at("geom1");
    k.geom2 = c.at("geom2");
    k.body1 = c.at("body1");
    k.body2 = c.at("body2");
    k.pos = c.at("pos").get<std::array<double, 3>>();
    k.normal = c.at("normal").get<std::array<double, 3>>();
    k.dist = c.at("dist");
    k.force = c.at("force").get<std::array<double, 6>>();
    out.push_back(std::move(k));
  }
  if (truncated) *truncated = reply.at("truncated").get<bool>();
  return out;
}

}  // namespace urlab::client
