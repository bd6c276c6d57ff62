#include "app/run_network.h"

#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>

#include "urlab/core/version.h"

namespace urlab::app {

namespace {

// `endpoint` with its port replaced by `port` (a number or "*"); endpoints that are not
// tcp://host:port (ipc://, inproc://, "") come back unchanged.
std::string WithPort(const std::string& endpoint, const std::string& port) {
  if (!endpoint.starts_with("tcp://")) return endpoint;
  const auto colon = endpoint.rfind(':');
  const auto bracket = endpoint.rfind(']');  // tcp://[::1]:5555
  if (colon == std::string::npos || colon < 6 ||
      (bracket != std::string::npos && colon < bracket)) {
    return endpoint;
  }
  return endpoint.substr(0, colon + 1) + port;
}

}  // namespace

void ChooseNetworkPorts(net::NetworkConfig& n, const std::string& ports, int port_base) {
  if (ports == "auto") {
    for (std::string* e : {&n.state, &n.control, &n.info, &n.rpc}) *e = WithPort(*e, "*");
    return;
  }
  if (port_base <= 0) return;
  n.state = WithPort(n.state, std::to_string(port_base));
  n.control = WithPort(n.control, std::to_string(port_base + 1));
  n.info = WithPort(n.info, std::to_string(port_base + 2));
  n.camera_base_port = port_base + 3;
  n.rpc = WithPort(n.rpc, std::to_string(port_base + 4));
}

std::string SceneName(const std::string& scene_path) {
  return std::filesystem::path(scene_path).stem().string();
}

std::string NewServerSession() {
  std::random_device random;
  std::uniform_int_distribution<unsigned> nibble(0, 15);
  std::string id;
  for (int i = 0; i < 16; ++i) id += "0123456789abcdef"[nibble(random)];
  return id;
}

std::string AnnounceJson(const net::NetworkOptions& options,
                         const net::NetworkSubsystem::Endpoints& bound,
                         const world::CameraStreams* cameras) {
  nlohmann::ordered_json j;
  j["format"] = 1;
  j["pid"] = static_cast<long>(::getpid());
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  j["host"] = host;
  j["urlab_version"] = kVersion;
  j["scene"] = options.scene_name;
  j["instance"] = options.instance;
  j["session"] = options.server_session;
  const auto or_null = [](const std::string& e) {
    return e.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(e);
  };
  j["endpoints"] = {{"state", or_null(bound.state)},
                    {"control", or_null(bound.control)},
                    {"info", or_null(bound.info)},
                    {"rpc", or_null(bound.rpc)}};
  nlohmann::ordered_json cams = nlohmann::ordered_json::array();
  if (cameras) {
    for (const world::CameraStreamInfo& s : cameras->Streams()) {
      if (s.endpoint.empty()) continue;
      cams.push_back({{"articulation", s.articulation},
                      {"stream", s.stream},
                      {"topic", s.topic},
                      {"endpoint", s.endpoint}});
    }
  }
  j["cameras"] = std::move(cams);
  // How a client can reach the step server, best first. Other transports add their offer here.
  nlohmann::ordered_json transports = nlohmann::ordered_json::array();
  if (!bound.rpc.empty()) transports.push_back({{"kind", "zmq"}, {"endpoint", bound.rpc}});
  j["transports"] = std::move(transports);
  return j.dump(2) + "\n";
}

}  // namespace urlab::app
