// libFuzzer target for the step server's request path (src/net/step_server.h): a StepServer over
// a real world::Session (the arm of fuzz_support.h, engine not started: commands run on this
// thread), bound to an inproc:// ROUTER endpoint, answers each input sent as one request from a
// DEALER socket; inputs up to the server's request limit (kMaxRequestBytes, tools/fuzz.sh's
// -max_len, asked from this target). msgpack or JSON as the server detects it (JSON when the first
// byte is '{', ' ' or '\n'). Every request must get exactly one reply, in the request's encoding,
// that is a map whose "op" is "error" (with string "code" and "message") or ends in "_ok"; never a
// crash.
//
// Before each input the harness says hello itself, and every occurrence of the 20-byte
// placeholder "@@@@@@@@@@@@@@@@@@@@" in the input becomes that session id (also 20 bytes, so a
// msgpack string keeps its length), so that inputs reach the operations that need a session
// and the driver lease. Between inputs the state, the options and the pause are reset, the files
// folder (a private temporary one) is emptied, and the harness ends every session and sets live
// mode again (clients, lease and mode start afresh; one server and one client serve the whole
// run). URLAB_FUZZ_VERBOSE=1 prints each reply (to read
// what a reproducer got).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>
#include <zmq.hpp>

#include "fuzz_support.h"
#include "net/step_server.h"
#include "net/topic_table.h"
#include "urlab/core/error.h"
#include "urlab/physics/commands.h"
#include "wire/request_limits.h"

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
  // One server and one client for the whole run (sockets closed per input would be freed later
  // by ZeroMQ's reaper thread, which makes every input look like a leak to libFuzzer).
  std::unique_ptr<urlab::net::StepServer> server;
  std::optional<zmq::socket_t> client;

  Fixture() {
    urlab::net::StepServerOptions o;
    o.endpoint = "inproc://urlab-fuzz-step";
    o.files_dir = urlab::fuzz::TempDir() + "/files";  // file operations write only there
    server = std::make_unique<urlab::net::StepServer>(*session, tables, state, o);
    if (server->Bind(context).empty()) __builtin_trap();
    client.emplace(context, zmq::socket_type::dealer);
    client->set(zmq::sockopt::linger, 0);
    client->set(zmq::sockopt::rcvtimeo, 1000);
    client->connect(o.endpoint);
  }
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

std::string Bytes(const Json& j) {
  const std::vector<std::uint8_t> b = Json::to_msgpack(j);
  return std::string(b.begin(), b.end());
}

Json Decode(const std::string& frame, bool json) {
  const auto* b = reinterpret_cast<const std::uint8_t*>(frame.data());
  return json ? Json::parse(b, b + frame.size(), nullptr, false)
              : Json::from_msgpack(b, b + frame.size(), true, false);
}

}  // namespace

// The fixture is built before the first input (its allocations are not the input's).
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  urlab::fuzz::AnswerMaxLenQuery(urlab::wire::kMaxRequestBytes);  // the server's request limit
  (void)F();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = F();
  if (std::getenv("URLAB_FUZZ_VERBOSE")) std::fprintf(stderr, "input of %zu bytes\n", size);
  urlab::net::StepServer& server = *f.server;
  zmq::socket_t& client = *f.client;
  urlab::physics::PhysicsEngine& engine = f.session->engine();
  // A fresh start: options as built, running, every articulation in its initial keyframe.
  const mjOption saved = f.options;
  (void)engine.Submit(urlab::physics::cmd::SetOptions{[saved](mjOption& o) { o = saved; },
                                                      "fuzz: options as built"});
  (void)engine.Submit(urlab::physics::cmd::SetPaused{false});
  (void)f.session->ResetToInitialState();
  // No file from an earlier input (file operations answer by what exists: file_exists).
  std::error_code ec;
  std::filesystem::remove_all(urlab::fuzz::TempDir() + "/files", ec);

  const std::vector<std::string> hello = Exchange(server, client, Bytes({{"op", "hello"}}));
  CheckReply(hello, false);
  const std::string id = Decode(hello[0], false).value("session_id", std::string());
  if (id.size() != kPlaceholder.size()) __builtin_trap();

  std::string request(reinterpret_cast<const char*>(data), size);
  for (std::size_t at = request.find(kPlaceholder); at != std::string::npos;
       at = request.find(kPlaceholder, at + id.size())) {
    request.replace(at, kPlaceholder.size(), id);
  }
  const bool json = IsJsonRequest(request);
  const std::vector<std::string> reply = Exchange(server, client, request);
  if (std::getenv("URLAB_FUZZ_VERBOSE") && reply.size() == 1) {  // to read a reproducer's reply
    std::fprintf(stderr, "reply: %s\n",
                 Decode(reply[0], json)
                     .dump(-1, ' ', false, Json::error_handler_t::replace)
                     .substr(0, 300)
                     .c_str());
  }
  CheckReply(reply, json);
  // Exactly one reply: nothing else arrives after serving once more.
  server.HandleIncoming();
  server.Service(urlab::net::StepServer::Clock::now());
  zmq::message_t extra;
  if (client.recv(extra, zmq::recv_flags::dontwait)) __builtin_trap();

  // Back to no clients and live mode for the next input: the harness's session sets the mode
  // (taking the lease) and says bye, and so does a session the input opened with hello.
  (void)Exchange(
      server, client,
      Bytes({{"op", "set_mode"}, {"session_id", id}, {"mode", "live"}, {"force", true}}));
  (void)Exchange(server, client, Bytes({{"op", "bye"}, {"session_id", id}}));
  const Json r = Decode(reply[0], json);
  if (r.value("op", "") == "hello_ok" && r.contains("session_id")) {
    (void)Exchange(server, client, Bytes({{"op", "bye"}, {"session_id", r["session_id"]}}));
  }
  (void)engine.DrainEvents();  // nobody else delivers them (a leak to libFuzzer otherwise)
  return 0;
}
