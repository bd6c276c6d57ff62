#pragma once
// A REQ client of the step server for tests: msgpack (or JSON text) requests, the session of the
// last hello added to every operation. One thread.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>
#include <zmq.hpp>

namespace urlab::net::test_client {

using Json = nlohmann::json;

// One REQ client speaking msgpack (or JSON text).
class Client {
 public:
  Client(zmq::context_t& ctx, const std::string& endpoint, bool json = false)
      : socket_(ctx, zmq::socket_type::req), json_(json) {
    socket_.set(zmq::sockopt::linger, 0);
    socket_.set(zmq::sockopt::rcvtimeo, 60000);  // a hang guard on a loaded machine
    socket_.connect(endpoint);
  }
  Json Call(const Json& request) {
    if (json_) {
      socket_.send(zmq::buffer(request.dump()));
    } else {
      const std::vector<std::uint8_t> bytes = Json::to_msgpack(request);
      socket_.send(zmq::buffer(bytes));
    }
    zmq::message_t reply;
    if (!socket_.recv(reply)) return Json{{"op", "timeout"}};
    const auto* b = static_cast<const std::uint8_t*>(reply.data());
    return json_ ? Json::parse(b, b + reply.size()) : Json::from_msgpack(b, b + reply.size());
  }
  Json CallRaw(const std::string& bytes) {
    socket_.send(zmq::buffer(bytes));
    zmq::message_t reply;
    if (!socket_.recv(reply)) return Json{{"op", "timeout"}};
    const auto* b = static_cast<const std::uint8_t*>(reply.data());
    return Json::from_msgpack(b, b + reply.size(), true, false);
  }
  // hello, remembering the session.
  Json Hello(Json extra = Json::object()) {
    extra["op"] = "hello";
    Json r = Call(extra);
    session_ = r.value("session_id", "");
    return r;
  }
  Json Op(const std::string& op, Json fields = Json::object()) {
    fields["op"] = op;
    fields["session_id"] = session_;
    return Call(fields);
  }
  const std::string& session() const { return session_; }

 private:
  zmq::socket_t socket_;
  bool json_;
  std::string session_;
};

}  // namespace urlab::net::test_client
