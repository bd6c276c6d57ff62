// libFuzzer target for the step server's request path (src/net/step_server.h): a StepServer over
// a real world::Session (the arm of fuzz_support.h, engine not started: commands run on this
// thread), bound to an inproc:// ROUTER endpoint, answers each input sent as one request from a
// DEALER socket. msgpack or JSON as the server detects it (JSON when the first byte is '{', ' '
// or '\n'). Every request must get exactly one reply, in the request's encoding, that is a map
// whose "op" is "error" (with string "code" and "message") or ends in "_ok"; never a crash.
//
// Before each input the harness says hello itself, and every occurrence of the 20-byte
// placeholder "@@@@@@@@@@@@@@@@@@@@" in the input becomes that session id (also 20 bytes, so a
// msgpack string keeps its length), so that inputs reach the operations that need a session
// and the driver lease. Between inputs the state, the options and the pause are reset and the
// server is rebuilt (clients, lease, mode start afresh). URLAB_FUZZ_VERBOSE=1 prints each reply
// (to read what a reproducer got).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "fuzz_support.h"
#include "net/step_server.h"
#include "net/topic_table.h"
#include "urlab/core/error.h"
#include "urlab/physics/commands.h"

namespace {

using Json = nlohmann::json;
constexpr std::string_view kPlaceholder = "@@@@@@@@@@@@@@@@@@@@";

struct Fixture {
  std::shared_ptr<urlab::world::Session> session = urlab::fuzz::MakeArmSession();
  std::vector<urlab::net::ArticulationTopics> tables = urlab::net::BuildTopicTables(*session);
  std::shared_ptr<urlab::physics::StateSubscription> state =
      session->engine().SubscribeState("fuzz_step_request");
  mjOption options = session->engine().model()->opt;  // as built, restored for each input
  zmq::context_t context{1};
  std::uint64_t endpoints = 0;
};

Fixture& F() {
  static Fixture f;
  return f;
}

// Sends `request` and serves until the reply arrives; the reply's frames (empty: none came).
std::vector<std::string> Exchange(urlab::net::StepServer& server, zmq::socket_t& client,
                                  std::string_view request) {
  client.send(zmq::buffer(request.data(), request.size()), zmq::send_flags::none);
  std::vector<std::string> frames;
  for (int attempt = 0; attempt < 2000 && frames.empty(); ++attempt) {
    server.HandleIncoming();
    server.Service(urlab::net::StepServer::Clock::now());
    zmq::message_t m;
    while (client.recv(m, attempt < 10 ? zmq::recv_flags::dontwait : zmq::recv_flags::none)) {
      frames.emplace_back(m.to_string());
      if (!m.more()) break;
    }
  }
  return frames;
}

bool IsJsonRequest(std::string_view bytes) {
  return !bytes.empty() && (bytes[0] == '{' || bytes[0] == ' ' || bytes[0] == '\n');
}

// A well-formed reply: one frame, the request's encoding, "op" error (code, message) or *_ok.
void CheckReply(const std::vector<std::string>& frames, bool json) {
  if (frames.size() != 1) __builtin_trap();
  const auto* b = reinterpret_cast<const std::uint8_t*>(frames[0].data());
  const Json reply = json ? Json::parse(b, b + frames[0].size(), nullptr, false)
                          : Json::from_msgpack(b, b + frames[0].size(), true, false);
  if (reply.is_discarded() || !reply.is_object()) __builtin_trap();
  const auto op = reply.find("op");
  if (op == reply.end() || !op->is_string()) __builtin_trap();
  const std::string name = op->get<std::string>();
  if (name == "error") {
    const auto code = reply.find("code"), message = reply.find("message");
    if (code == reply.end() || !code->is_string() || message == reply.end() ||
        !message->is_string()) {
      __builtin_trap();
    }
  } else if (name.size() < 3 || name.compare(name.size() - 3, 3, "_ok") != 0) {
    __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = F();
  urlab::physics::PhysicsEngine& engine = f.session->engine();
  // A fresh start: options as built, running, every articulation in its initial keyframe.
  const mjOption saved = f.options;
  (void)engine.Submit(urlab::physics::cmd::SetOptions{[saved](mjOption& o) { o = saved; },
                                                      "fuzz: options as built"});
  (void)engine.Submit(urlab::physics::cmd::SetPaused{false});
  (void)f.session->ResetToInitialState();

  urlab::net::StepServerOptions options;
  // A new name each time: a closed socket's inproc name is released asynchronously.
  options.endpoint = "inproc://urlab-fuzz-step-" + std::to_string(f.endpoints++);
  urlab::net::StepServer server(*f.session, f.tables, f.state, options);
  if (server.Bind(f.context).empty()) __builtin_trap();
  zmq::socket_t client(f.context, zmq::socket_type::dealer);
  client.set(zmq::sockopt::linger, 0);
  client.set(zmq::sockopt::rcvtimeo, 1000);
  client.connect(options.endpoint);

  const std::vector<std::uint8_t> hello = Json::to_msgpack(Json{{"op", "hello"}});
  const std::vector<std::string> hello_reply = Exchange(
      server, client, std::string_view(reinterpret_cast<const char*>(hello.data()), hello.size()));
  CheckReply(hello_reply, false);
  const auto* hb = reinterpret_cast<const std::uint8_t*>(hello_reply[0].data());
  const std::string id =
      Json::from_msgpack(hb, hb + hello_reply[0].size()).value("session_id", std::string());
  if (id.size() != kPlaceholder.size()) __builtin_trap();

  std::string request(reinterpret_cast<const char*>(data), size);
  for (std::size_t at = request.find(kPlaceholder); at != std::string::npos;
       at = request.find(kPlaceholder, at + id.size())) {
    request.replace(at, kPlaceholder.size(), id);
  }
  const std::vector<std::string> reply = Exchange(server, client, request);
  if (std::getenv("URLAB_FUZZ_VERBOSE") && reply.size() == 1) {  // to read a reproducer's reply
    const auto* rb = reinterpret_cast<const std::uint8_t*>(reply[0].data());
    const Json r = IsJsonRequest(request)
                       ? Json::parse(rb, rb + reply[0].size(), nullptr, false)
                       : Json::from_msgpack(rb, rb + reply[0].size(), true, false);
    std::fprintf(stderr, "reply: %s\n",
                 r.dump(-1, ' ', false, Json::error_handler_t::replace).substr(0, 300).c_str());
  }
  CheckReply(reply, IsJsonRequest(request));
  // Exactly one reply: nothing else arrives after serving once more.
  server.HandleIncoming();
  server.Service(urlab::net::StepServer::Clock::now());
  zmq::message_t extra;
  if (client.recv(extra, zmq::recv_flags::dontwait)) __builtin_trap();
  server.Close();
  return 0;
}
