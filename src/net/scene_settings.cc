// The network's scene section (urlab/net/scene_settings.h): what each key takes is data (the
// tables below); the reader's checks report a bad value at its file:line.
#include "urlab/net/scene_settings.h"

#include <any>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <string>
#include <string_view>

#include "world/scene_section.h"

namespace urlab::net {

namespace {

namespace fs = std::filesystem;
using world::SectionReader;

// An endpoint: any text ZeroMQ takes (tcp://host:port, ipc://path...); "" : no socket.
struct Endpoint {
  const char* key;
  std::string NetworkConfig::*field;
};
constexpr Endpoint kEndpoints[] = {{"state", &NetworkConfig::state},
                                   {"control", &NetworkConfig::control},
                                   {"info", &NetworkConfig::info},
                                   {"rpc", &NetworkConfig::rpc}};

// A word from a list; `none` (when given) stands for "" (off).
struct Choice {
  const char* key;
  std::string NetworkConfig::*field;
  std::vector<std::string> words;
  const char* none;  // the word meaning "", nullptr when there is none
  const char* message;
};
const Choice kChoices[] = {
    {"full_state",
     &NetworkConfig::full_state,
     {"minimal", "standard", "full"},
     "none",
     "network.full_state must be minimal, standard, full or none"},
    {"step_mode",
     &NetworkConfig::step_mode,
     {"live", "direct"},
     nullptr,
     "network.step_mode must be live or direct"},
};

// The port of a tcp:// or ws:// endpoint; 0 for "*" and for other transports.
int TcpPort(const std::string& endpoint) {
  if (!endpoint.starts_with("tcp://") && !endpoint.starts_with("ws://")) return 0;
  const auto colon = endpoint.rfind(':');
  if (colon == std::string::npos) return 0;
  return std::atoi(endpoint.c_str() + colon + 1);
}

// "" when ZeroMQ can bind `endpoint` as written (or it is "", no socket), else what it should
// look like.
std::string EndpointProblem(const std::string& endpoint) {
  if (endpoint.empty()) return "";
  const std::string shapes = "tcp://HOST:PORT, ipc://PATH or inproc://NAME";
  for (const char* scheme : {"ipc://", "inproc://"}) {
    if (endpoint.starts_with(scheme)) {
      return endpoint.size() > std::string_view(scheme).size() ? "" : shapes;
    }
  }
  for (const char* scheme : {"tcp://", "ws://"}) {
    if (!endpoint.starts_with(scheme)) continue;
    const std::string rest = endpoint.substr(std::string_view(scheme).size());
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || colon == 0) return shapes;
    std::string port = rest.substr(colon + 1);
    const auto slash = port.find('/');  // ws://host:port/path
    if (slash != std::string::npos && std::string_view(scheme) == "ws://") port.resize(slash);
    if (port == "*") return "";
    if (port.empty() || port.size() > 5 ||
        port.find_first_not_of("0123456789") != std::string::npos) {
      return "port 1 to 65535 or *";
    }
    const int p = std::atoi(port.c_str());
    return p >= 1 && p <= 65535 ? "" : "port 1 to 65535 or *";
  }
  return shapes;
}

// network: {enabled, state, control, info, rpc, step_mode, full_state, camera_base_port,
// files_dir, max_queued_steps}.
std::any Parse(const SectionReader& r, const YAML::Node& n, const world::SceneConfig&) {
  NetworkConfig c;
  c.where = r.At(n);
  r.CheckKeys(n, "network",
              {"enabled", "state", "control", "info", "rpc", "step_mode", "full_state",
               "camera_base_port", "files_dir", "max_queued_steps"});
  if (n["enabled"]) c.enabled = r.Bool(n["enabled"], "network.enabled");
  for (const Endpoint& e : kEndpoints) {
    const YAML::Node v = n[e.key];
    if (!v) continue;
    const std::string field = std::string("network.") + e.key;
    c.*e.field = r.String(v, field);
    if (const std::string problem = EndpointProblem(c.*e.field); !problem.empty()) {
      r.Fail(v, field + ": '" + c.*e.field + "' is not an endpoint (" + problem + ")");
    }
  }
  // Two sockets cannot bind one endpoint (or one TCP port): the later one is refused at its
  // line, against the earlier one given or by default. Ports the system chooses (*) differ.
  for (std::size_t i = 0; i < std::size(kEndpoints); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const Endpoint& a = kEndpoints[j];
      const Endpoint& b = kEndpoints[i];
      const std::string& ea = c.*a.field;
      const std::string& eb = c.*b.field;
      if (ea.empty() || eb.empty()) continue;
      const int pa = TcpPort(ea), pb = TcpPort(eb);
      const bool same_port = pa > 0 && pa == pb;
      if (ea != eb && !same_port) continue;
      if (ea == eb && ea.starts_with("tcp://") && pa == 0) continue;  // "*": the system's
      const YAML::Node at = n[b.key] ? n[b.key] : n[a.key] ? n[a.key] : n;
      r.Fail(at, std::string("network.") + b.key + ": " + eb + " is network." + a.key + "'s " +
                     (same_port ? "port " + std::to_string(pa) + " " : std::string()) +
                     "too (each socket needs its own)");
    }
  }
  for (const Choice& ch : kChoices) {
    const YAML::Node v = n[ch.key];
    if (!v) continue;
    std::string word = r.String(v, std::string("network.") + ch.key);
    if (ch.none && word == ch.none) word.clear();
    if (!word.empty() || !ch.none) {
      bool known = false;
      for (const std::string& w : ch.words) known |= w == word;
      if (!known) r.Fail(v, ch.message);
    }
    c.*ch.field = word;
  }
  if (n["camera_base_port"]) {
    // A TCP port: the first camera stream binds it, the next ones the ports above.
    c.camera_base_port = r.Whole(n["camera_base_port"], "network.camera_base_port", 1, 65535);
  }
  if (const auto d = n["files_dir"]) {
    const std::string text = r.String(d, "network.files_dir");
    if (text.empty()) r.Fail(d, "network.files_dir must name a folder (or leave it out)");
    fs::path p(text);
    if (p.is_relative()) p = fs::path(r.path()).parent_path() / p;
    c.files_dir = fs::absolute(p).lexically_normal().string();
    std::error_code ec;
    if (fs::exists(c.files_dir, ec) && !fs::is_directory(c.files_dir, ec)) {
      r.Fail(d, "network.files_dir: " + c.files_dir + " exists and is not a folder");
    }
  }
  if (const auto q = n["max_queued_steps"]) {
    c.max_queued_steps =
        static_cast<std::size_t>(r.Whole(q, "network.max_queued_steps", 1, 10000000));
  }
  return c;
}

}  // namespace

void RegisterSceneSections() { world::RegisterSceneSection({kNetworkSection, &Parse}); }

const NetworkConfig& NetworkOf(const world::SceneConfig& scene) {
  static const NetworkConfig kDefaults;
  const auto* c = scene.sections.Get<NetworkConfig>(kNetworkSection);
  return c ? *c : kDefaults;
}

NetworkConfig& EditNetwork(world::SceneConfig& scene) {
  return scene.sections.GetOrAdd<NetworkConfig>(kNetworkSection);
}

std::vector<int> EndpointPorts(const NetworkConfig& network) {
  std::vector<int> out;
  for (const Endpoint& e : kEndpoints) {
    const std::string& endpoint = network.*e.field;
    const auto colon = endpoint.rfind(':');
    if (colon == std::string::npos) continue;
    const int used = std::atoi(endpoint.c_str() + colon + 1);
    if (used > 0) out.push_back(used);
  }
  return out;
}

}  // namespace urlab::net
