// The network's scene section (urlab/net/scene_settings.h): what each key takes is data (the
// tables below); the reader's checks report a bad value at its file:line.
#include "urlab/net/scene_settings.h"

#include <any>
#include <cstdlib>
#include <filesystem>

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
    if (n[e.key]) c.*e.field = r.String(n[e.key], std::string("network.") + e.key);
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
